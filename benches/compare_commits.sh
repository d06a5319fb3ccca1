#!/usr/bin/env bash
# Instruction-count comparison of `risotto render` between two commits.
#
# Wall-clock benches on a shared machine drift by +-15% with the load; the number of
# instructions executed (valgrind callgrind, total Ir) does not. For each scene the render
# runs single-threaded at two sample counts, so the fixed cost (scene load, BVH build, EXR
# write) cancels out of the marginal figure:
#
#   Ir per camera sample = (Ir(spp_hi) - Ir(spp_lo)) / (samples(spp_hi) - samples(spp_lo))
#
# Both commits are built (release) in temporary worktrees under target/compare_commits/,
# sharing one CARGO_TARGET_DIR there; binaries are cached by commit hash
# (`rm -r target/compare_commits` forces a rebuild, e.g. after a toolchain change).
# The callgrind profiles stay there for `callgrind_annotate`.
set -euo pipefail

usage() {
    cat >&2 <<'EOF'
usage: benches/compare_commits.sh OLD NEW [SCENE:SPP_LO:SPP_HI ...]

  OLD, NEW   any commit-ish (hash, branch, tag, HEAD~1)
  SCENE      scene path relative to the repository root; it (and the files it names
             with `path`/`map = "..."`) must be identical at both commits
  SPP_LO/HI  the two sample counts (SPP_HI > SPP_LO >= 1)

Default scenes: scenes/mitsuba-suite/cornell.toml:2:10 scenes/glass-sphere.toml:1:4
                scenes/mesh.toml:1:4
Prints, per scene, total Ir at SPP_HI and the marginal Ir per camera sample for both
commits and the ratio NEW/OLD (< 1 means NEW executes fewer instructions).
Needs: git, cargo, valgrind, awk. Takes a few minutes per scene.
EOF
    exit 2
}

die() {
    echo "compare_commits: $*" >&2
    exit 1
}

[[ $# -ge 2 ]] || usage
[[ $1 == -h || $1 == --help ]] && usage
command -v valgrind >/dev/null || die "valgrind not found"
command -v cargo >/dev/null || die "cargo not found"

root=$(git rev-parse --show-toplevel) || die "not inside a git checkout"
old=$(git -C "$root" rev-parse --verify --quiet "$1^{commit}") || die "not a commit: $1"
new=$(git -C "$root" rev-parse --verify --quiet "$2^{commit}") || die "not a commit: $2"
shift 2
if [[ $# -gt 0 ]]; then
    specs=("$@")
else
    specs=(scenes/mitsuba-suite/cornell.toml:2:10 scenes/glass-sphere.toml:1:4 scenes/mesh.toml:1:4)
fi

work="$root/target/compare_commits"
mkdir -p "$work"
trees=()
cleanup() {
    for t in "${trees[@]+"${trees[@]}"}"; do
        git -C "$root" worktree remove --force "$t" || echo "could not remove worktree $t" >&2
    done
}
trap cleanup EXIT

# Checks out commit $1 into a temporary worktree and builds its driver into
# $work/risotto-<hash> unless that binary exists already.
prepare() {
    local commit=$1 tree="$work/tree-${1:0:12}" bin="$work/risotto-${1:0:12}"
    if [[ -e $tree ]]; then
        git -C "$root" worktree remove --force "$tree" 2>/dev/null || rm -rf "$tree"
        git -C "$root" worktree prune
    fi
    git -C "$root" worktree add --detach --quiet "$tree" "$commit" >&2
    trees+=("$tree")
    if [[ ! -x $bin ]]; then
        echo "building ${commit:0:12} ..." >&2
        (cd "$tree" && CARGO_TARGET_DIR="$work/target" cargo build --release --quiet --bin risotto) >&2 ||
            die "build of ${commit:0:12} failed"
        cp "$work/target/release/risotto" "$bin.tmp"
        mv "$bin.tmp" "$bin"
    fi
}

# Check every spec before the (long) builds.
for spec in "${specs[@]}"; do
    IFS=: read -r scene lo hi <<<"$spec"
    [[ -n ${scene:-} && ${lo:-} =~ ^[0-9]+$ && ${hi:-} =~ ^[0-9]+$ && $lo -ge 1 && $hi -gt $lo ]] ||
        die "bad spec '$spec' (want SCENE:SPP_LO:SPP_HI with SPP_HI > SPP_LO >= 1)"
    git -C "$root" cat-file -e "$old:$scene" 2>/dev/null || die "$scene does not exist at ${old:0:12}"
    git -C "$root" cat-file -e "$new:$scene" 2>/dev/null || die "$scene does not exist at ${new:0:12}"
    # The scene and the files it references must be the same, or the ratio means nothing.
    deps=("$scene")
    while read -r p; do
        [[ $p == /* ]] && continue # absolute: outside the repository, same for both
        deps+=("$(realpath -m --relative-to="$root" "$root/$(dirname "$scene")/$p")")
    done < <(git -C "$root" show "$new:$scene" | sed -n -E 's/^[[:space:]]*(path|map)[[:space:]]*=[[:space:]]*"([^"]*)".*/\2/p')
    git -C "$root" diff --quiet "$old" "$new" -- "${deps[@]}" ||
        die "$scene or a file it references differs between the commits"
done

prepare "$old"
prepare "$new"

# Runs one render under callgrind; prints "Ir samples rays".
measure() {
    local commit=$1 scene=$2 spp=$3
    local tag="${commit:0:12}-$(basename "$scene" .toml)-$spp"
    local tree="$work/tree-${commit:0:12}" bin="$work/risotto-${commit:0:12}"
    valgrind --tool=callgrind --collect-atstart=yes --callgrind-out-file="$work/cg-$tag.out" \
        "$bin" render "$tree/$scene" --spp "$spp" --threads 1 --quiet \
        --out "$work/out-$tag.exr" --stats "$work/stats-$tag.json" 2>"$work/valgrind-$tag.log" ||
        die "render failed, see $work/valgrind-$tag.log"
    local ir samples rays
    ir=$(awk '/^totals:/ {print $2}' "$work/cg-$tag.out")
    samples=$(grep -o '"samples": *[0-9]*' "$work/stats-$tag.json" | grep -o '[0-9]*$')
    rays=$(grep -o '"rays": *[0-9]*' "$work/stats-$tag.json" | grep -o '[0-9]*$')
    [[ -n $ir && -n $samples && -n $rays ]] || die "could not read Ir/samples/rays for $tag"
    echo "$ir $samples $rays"
}

echo "old ${old:0:12}  $(git -C "$root" log -1 --format=%s "$old")"
echo "new ${new:0:12}  $(git -C "$root" log -1 --format=%s "$new")"
printf '\n%-34s %4s %15s %15s %7s | %11s %11s %7s | %s\n' scene spp "Ir old" "Ir new" ratio \
    "Ir/smp old" "Ir/smp new" ratio "rays old/new"
for spec in "${specs[@]}"; do
    IFS=: read -r scene lo hi <<<"$spec"
    # Plain assignments, so that a failing measurement stops the script (set -e).
    m_ol=$(measure "$old" "$scene" "$lo")
    m_oh=$(measure "$old" "$scene" "$hi")
    m_nl=$(measure "$new" "$scene" "$lo")
    m_nh=$(measure "$new" "$scene" "$hi")
    read -r ir_ol s_ol r_ol <<<"$m_ol"
    read -r ir_oh s_oh r_oh <<<"$m_oh"
    read -r ir_nl s_nl r_nl <<<"$m_nl"
    read -r ir_nh s_nh r_nh <<<"$m_nh"
    [[ $s_ol == "$s_nl" && $s_oh == "$s_nh" ]] || die "sample counts differ for $scene"
    awk -v sc="$scene" -v hi="$hi" -v a="$ir_oh" -v b="$ir_nh" -v al="$ir_ol" -v bl="$ir_nl" \
        -v sl="$s_ol" -v sh="$s_oh" -v ro="$r_oh" -v rn="$r_nh" 'BEGIN {
        po = (a - al) / (sh - sl); pn = (b - bl) / (sh - sl);
        printf "%-34s %4d %15.0f %15.0f %7.4f | %11.0f %11.0f %7.4f | %d/%d\n",
            sc, hi, a, b, b / a, po, pn, pn / po, ro, rn }'
done
echo
echo "profiles: $work/cg-<commit>-<scene>-<spp>.out (callgrind_annotate OLD.out / NEW.out)"
