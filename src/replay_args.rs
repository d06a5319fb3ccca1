//! `risotto render --replay X,Y,SAMPLE`: parsing the flag, and the render command that
//! re-runs a non-finite case's path (printed with each case; `engine::replay` does the work).

use crate::render_args::RenderArgs;
use anyhow::{Context, Result};

/// Parses `--replay X,Y,SAMPLE`.
pub(crate) fn parse_replay(s: &str) -> Result<(u32, u32, u32)> {
    let v: Vec<&str> = s.split(',').collect();
    anyhow::ensure!(
        v.len() == 3,
        "--replay {s}: expected three whole numbers X,Y,SAMPLE (pixel column, row, sample index)"
    );
    let mut n = [0u32; 3];
    for (i, t) in v.iter().enumerate() {
        n[i] = t
            .trim()
            .parse()
            .with_context(|| format!("--replay {s}: \"{t}\" is not a whole number"))?;
    }
    Ok((n[0], n[1], n[2]))
}

/// The `risotto render` command with the options of `args` that decide a path (scene, spp,
/// seed, depth, techniques), to which a non-finite case's `--replay X,Y,SAMPLE` is appended.
pub(crate) fn replay_base_command(args: &RenderArgs) -> String {
    /// `s`, single-quoted for a POSIX shell when it holds anything but plain characters.
    fn quoted(s: &str) -> String {
        let plain = |c: char| c.is_ascii_alphanumeric() || "-_./=+,:@%".contains(c);
        if !s.is_empty() && s.chars().all(plain) {
            s.to_string()
        } else {
            format!("'{}'", s.replace('\'', "'\\''"))
        }
    }
    let mut cmd = format!("risotto render {}", quoted(&args.scene.to_string_lossy()));
    for d in &args.defines {
        cmd += &format!(" -D {}", quoted(d));
    }
    if let Some(size) = &args.size {
        cmd += &format!(" --size {}", quoted(size));
    }
    if let Some(spp) = args.spp {
        cmd += &format!(" --spp {spp}");
    }
    if let Some(seed) = args.seed {
        cmd += &format!(" --seed {seed}");
    }
    if let Some(d) = args.max_depth {
        cmd += &format!(" --max-depth {d}");
    }
    if let Some(l) = &args.lighting {
        cmd += &format!(" --lighting {}", quoted(l));
    }
    for t in &args.techniques {
        cmd += &format!(" --technique {}", quoted(t));
    }
    cmd
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Cli, Command};
    use clap::Parser;

    fn render_args(args: &[&str]) -> RenderArgs {
        let argv = ["risotto", "render"].iter().chain(args);
        match Cli::try_parse_from(argv).unwrap().command {
            Command::Render(a) => *a,
            _ => unreachable!("a render command"),
        }
    }

    #[test]
    fn the_replay_command_keeps_what_decides_a_path_and_quotes_the_scene() {
        let a = render_args(&[
            "my scene.toml",
            "--spp",
            "16",
            "--seed",
            "3",
            "--threads",
            "2",
            "--out",
            "x.exr",
            "--technique",
            "sampler=independent",
            "--max-depth",
            "-1",
        ]);
        assert_eq!(
            replay_base_command(&a),
            "risotto render 'my scene.toml' --spp 16 --seed 3 --max-depth -1 \
             --technique sampler=independent"
        );
        let a = render_args(&["scenes/it's.toml", "--lighting", "nee"]);
        assert_eq!(
            replay_base_command(&a),
            "risotto render 'scenes/it'\\''s.toml' --lighting nee"
        );
    }

    #[test]
    fn replay_values_parse_or_name_the_flag() {
        assert_eq!(parse_replay("3, 4,5").unwrap(), (3, 4, 5));
        for bad in ["3,4", "3,4,5,6", "a,1,2", "1,2,-3", ""] {
            let e = format!("{:#}", parse_replay(bad).unwrap_err());
            assert!(e.starts_with(&format!("--replay {bad}:")), "{e}");
        }
    }
}
