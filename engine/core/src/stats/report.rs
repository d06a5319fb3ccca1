//! How the render's stats are shown: the JSON of `--stats` ([`Serialize`] for
//! [`RenderStats`]) and the printed summary ([`fmt::Display`]).

use super::*;
use serde::ser::{Serialize, SerializeMap, Serializer};
use std::fmt;

/// `{"calls": n, "items": n, "seconds": s}`.
impl Serialize for SystemCounter {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(Some(3))?;
        m.serialize_entry("calls", &self.calls)?;
        m.serialize_entry("items", &self.items)?;
        m.serialize_entry("seconds", &self.seconds)?;
        m.end()
    }
}

/// Map keyed by system name, in [`System::ALL`] order, systems with zero calls omitted.
struct SystemsJson<'a>(&'a [SystemCounter; System::COUNT]);
impl Serialize for SystemsJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(None)?;
        for sys in System::ALL {
            let c = &self.0[sys as usize];
            if c.calls > 0 {
                m.serialize_entry(sys.name(), c)?;
            }
        }
        m.end()
    }
}

/// Map keyed by volume-event name, zero counts omitted.
struct VolumeEventsJson<'a>(&'a [u64; VolumeEvent::COUNT]);
impl Serialize for VolumeEventsJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(None)?;
        for e in VolumeEvent::ALL {
            let n = self.0[e as usize];
            if n > 0 {
                m.serialize_entry(e.name(), &n)?;
            }
        }
        m.end()
    }
}

/// Map keyed by stage name, zero counts omitted.
struct NonFiniteJson<'a>(&'a [u64; Stage::COUNT]);
impl Serialize for NonFiniteJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(None)?;
        for st in Stage::ALL {
            let n = self.0[st as usize];
            if n > 0 {
                m.serialize_entry(st.name(), &n)?;
            }
        }
        m.end()
    }
}

/// The kept non-finite cases, each with its replay command.
struct CasesJson<'a>(&'a RenderStats);
impl Serialize for CasesJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeSeq;
        let stats = self.0;
        let mut seq = s.serialize_seq(Some(stats.non_finite_cases.len()))?;
        for c in &stats.non_finite_cases {
            let mut m = serde_json::Map::new();
            m.insert("x".into(), c.x.into());
            m.insert("y".into(), c.y.into());
            m.insert("sample".into(), c.sample.into());
            m.insert("depth".into(), c.depth.into());
            m.insert("stage".into(), c.stage.name().into());
            if let Some(name) = &c.material {
                m.insert("material".into(), name.as_str().into());
            }
            m.insert("seed".into(), c.seed.into());
            m.insert("replay".into(), stats.replay_command(c).into());
            seq.serialize_element(&m)?;
        }
        seq.end()
    }
}

/// Map keyed by termination name, zero counts omitted.
struct TerminatedJson<'a>(&'a [u64; Termination::COUNT]);
impl Serialize for TerminatedJson<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut m = s.serialize_map(None)?;
        for t in Termination::ALL {
            let n = self.0[t as usize];
            if n > 0 {
                m.serialize_entry(t.name(), &n)?;
            }
        }
        m.end()
    }
}

impl Serialize for RenderStats {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let c = &self.counters;
        let mut m = s.serialize_map(None)?;
        if let Some(run) = &self.run {
            m.serialize_entry("run", run)?;
        }
        if let Some(a) = &self.adaptive {
            m.serialize_entry(
                "adaptive",
                &serde_json::json!({
                    "target": a.target,
                    "spp_min": a.spp_min,
                    "spp_mean": a.spp_mean,
                    "spp_max": a.spp_max,
                    "converged_fraction": a.converged_fraction,
                    // An estimate can be infinite (a pixel with variance and no light):
                    // JSON has no infinity, so such a quantile is written as null.
                    "error_median": finite_or_null(a.error_median),
                    "error_p95": finite_or_null(a.error_p95),
                    "pilot_spp": a.pilot_spp,
                    "passes": a.passes,
                    "plan_seconds": a.plan_seconds,
                }),
            )?;
        }
        m.serialize_entry("systems", &SystemsJson(&c.systems))?;
        m.serialize_entry("rays", &c.rays)?;
        m.serialize_entry("samples", &c.samples)?;
        m.serialize_entry("terminated", &TerminatedJson(&c.terminated))?;
        m.serialize_entry("nan_dropped", &c.nan_dropped)?;
        if c.non_finite.iter().any(|&n| n > 0) {
            m.serialize_entry("non_finite", &NonFiniteJson(&c.non_finite))?;
        }
        if !self.non_finite_cases.is_empty() {
            m.serialize_entry("non_finite_cases", &CasesJson(self))?;
        }
        if c.volume_events.iter().any(|&n| n > 0) {
            m.serialize_entry("volume_events", &VolumeEventsJson(&c.volume_events))?;
        }
        let heterogeneous = self.features.iter().any(|f| f == "heterogeneous_media");
        if heterogeneous || c.majorant_violations > 0 {
            m.serialize_entry("majorant_violations", &c.majorant_violations)?;
        }
        if heterogeneous {
            m.serialize_entry("shadow_collisions", &c.shadow_collisions)?;
        }
        if self.features.iter().any(|f| f == "terminator_offset") {
            m.serialize_entry("terminator_lifts", &c.terminator_lifts)?;
        }
        if c.dense_segments > 0 {
            m.serialize_entry("dense_segments", &c.dense_segments)?;
            m.serialize_entry("dense_lookups", &c.dense_lookups)?;
        }
        if c.pattern_cache_hits + c.pattern_evals > 0 {
            m.serialize_entry("pattern_cache_hits", &c.pattern_cache_hits)?;
            m.serialize_entry("pattern_cache_shared", &c.pattern_cache_shared)?;
            m.serialize_entry("pattern_evals", &c.pattern_evals)?;
            m.serialize_entry("volume_pattern_evals", &c.volume_pattern_evals)?;
        }
        if self.features.iter().any(|f| f == "opacity") {
            m.serialize_entry("opacity_tests", &c.opacity_tests)?;
            m.serialize_entry("opacity_passes", &c.opacity_passes)?;
            m.serialize_entry("opacity_shadow_crossings", &c.opacity_shadow_crossings)?;
        }
        if c.walked_subpath_rays > 0 {
            m.serialize_entry("walked_subpath_rays", &c.walked_subpath_rays)?;
        }
        if !c.bidir_rays.is_empty() {
            m.serialize_entry("bidir_rays", &c.bidir_rays)?;
        }
        m.serialize_entry("wall_seconds", &self.wall_seconds)?;
        m.serialize_entry("features", &self.features)?;
        if !self.warnings.is_empty() {
            m.serialize_entry("warnings", &self.warnings)?;
        }
        m.end()
    }
}

/// `x / t` as a rate, 0 when no time elapsed.
fn rate(x: f64, t: f64) -> f64 {
    if t > 0.0 {
        x / t
    } else {
        0.0
    }
}

/// `v` as JSON, `null` when not finite.
fn finite_or_null(v: f32) -> serde_json::Value {
    if v.is_finite() {
        serde_json::json!(v)
    } else {
        serde_json::Value::Null
    }
}

/// The human summary the driver prints.
impl fmt::Display for RenderStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = &self.counters;
        writeln!(
            f,
            "{:<14}{:>12}{:>14}{:>11}{:>11}",
            "system", "calls", "items", "seconds", "Mitems/s"
        )?;
        let mut total = 0.0;
        for sys in System::ALL {
            let s = &c.systems[sys as usize];
            if s.calls == 0 {
                continue;
            }
            total += s.seconds;
            writeln!(
                f,
                "{:<14}{:>12}{:>14}{:>11.3}{:>11.2}",
                sys.name(),
                s.calls,
                s.items,
                s.seconds,
                rate(s.items as f64, s.seconds) * 1e-6
            )?;
        }
        writeln!(f, "{:<14}{:>37.3}  (summed over workers)", "total", total)?;
        writeln!(
            f,
            "rays: {} ({:.2} Mrays/s), samples: {} ({:.3} Msamples/s), wall: {:.3} s",
            c.rays,
            rate(c.rays as f64, self.wall_seconds) * 1e-6,
            c.samples,
            rate(c.samples as f64, self.wall_seconds) * 1e-6,
            self.wall_seconds
        )?;
        if let Some(a) = &self.adaptive {
            writeln!(
                f,
                "adaptive: target {:.4}, spp {} / {:.1} / {} (min / mean / max), {:.1} % of \
                 pixels at the target, estimated error median {:.4}, 95th percentile {:.4}; \
                 {} passes, {:.3} s deciding between them",
                a.target,
                a.spp_min,
                a.spp_mean,
                a.spp_max,
                100.0 * a.converged_fraction,
                a.error_median,
                a.error_p95,
                a.passes,
                a.plan_seconds
            )?;
            if a.pilot_spp > 0 {
                writeln!(
                    f,
                    "adaptive: unbiased stopping rule, a pilot of {} spp decided (rendered, \
                     not in the image)",
                    a.pilot_spp
                )?;
            }
        }
        let ended: u64 = c.terminated.iter().sum();
        write!(f, "terminated:")?;
        if ended == 0 {
            write!(f, " none")?;
        }
        for t in Termination::ALL {
            let n = c.terminated[t as usize];
            if n > 0 {
                write!(
                    f,
                    " {} {} ({:.1}%)",
                    t.name(),
                    n,
                    100.0 * n as f64 / ended as f64
                )?;
            }
        }
        writeln!(f)?;
        if let Some(run) = &self.run {
            write!(
                f,
                "load {:.3} s, build {:.3} s, render {:.3} s on {} threads",
                run.load_seconds, run.build_seconds, run.render_seconds, run.threads
            )?;
            if let Some(s) = run.denoise_seconds {
                write!(f, ", denoise {s:.3} s")?;
            }
            if let Some(s) = run.output_seconds {
                write!(f, ", output {s:.3} s")?;
            }
            if let Some(bytes) = run.peak_resident_bytes {
                write!(
                    f,
                    ", peak memory {:.1} MiB",
                    bytes as f64 / (1u64 << 20) as f64
                )?;
            }
            writeln!(f)?;
        }
        write!(f, "nan dropped: {}", c.nan_dropped)?;
        if self.features.iter().any(|f| f == "opacity") {
            write!(
                f,
                "\nopacity: {} path-ray tests, {} passed; {} shadow-ray crossings",
                c.opacity_tests, c.opacity_passes, c.opacity_shadow_crossings
            )?;
        }
        if c.majorant_violations > 0 {
            write!(
                f,
                "\nwarning: {} sampled extinctions above their majorant (a wrong bound: the \
                 heterogeneous estimators are not unbiased there)",
                c.majorant_violations
            )?;
        }
        if c.dense_segments > 0 {
            write!(
                f,
                "\nwarning: {} majorant segments were too dense to track (more than {} \
                 expected collisions each: a majorant cell of extreme bound, e.g. one voxel far \
                 denser than its neighbours) and were integrated exactly along the voxel grid \
                 instead (unbiased, bounded work; see docs/scene-format.md, `majorant_grid`)",
                c.dense_segments,
                risotto_systems::tracking::dense::TRACKING_CAP
            )?;
        }
        let frozen = c.volume_events[VolumeEvent::Frozen as usize];
        if frozen > 0 {
            write!(
                f,
                "\nwarning: {frozen} paths ended frozen in a medium whose mean free path is far \
                 below the float spacing of its coordinates (its random walk cannot move \
                 there): that medium renders darker than it should; scale the scene, or use a \
                 surface or subsurface material for it"
            )?;
        }
        let cut = c.terminated[Termination::DepthLimit as usize];
        if cut > 0 {
            write!(
                f,
                "\nwarning: {cut} paths reached {} scattering vertices, the most a path can \
                 have, and were ended there (light that cannot leave a region: albedo-1 walls \
                 or media around it, or a medium too dense for its coordinates' precision); \
                 the image misses what they would have carried on",
                risotto_systems::path::MAX_PATH_VERTICES
            )?;
        }
        if c.non_finite.iter().any(|&n| n > 0) {
            write!(f, "\nnon-finite values by stage:")?;
            for st in Stage::ALL {
                let n = c.non_finite[st as usize];
                if n > 0 {
                    write!(f, " {} {n}", st.name())?;
                }
            }
        }
        for case in &self.non_finite_cases {
            write!(
                f,
                "\nnon-finite sample: pixel ({}, {}) sample {} depth {} stage {}",
                case.x,
                case.y,
                case.sample,
                case.depth,
                case.stage.name()
            )?;
            if let Some(name) = &case.material {
                write!(f, " material \"{name}\"")?;
            }
            write!(f, " seed {}: {}", case.seed, self.replay_command(case))?;
        }
        if !self.features.is_empty() {
            write!(f, "\nfeatures: {}", self.features.join(", "))?;
        }
        for w in &self.warnings {
            write!(f, "\nwarning: {w}")?;
        }
        Ok(())
    }
}
