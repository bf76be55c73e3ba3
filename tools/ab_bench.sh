#!/usr/bin/env bash
# Runs one criterion benchmark of two commits interleaved (A, B, A, B, ...), so that both see
# the same machine load; prints each round's medians. Not run by the tests.
#
#   tools/ab_bench.sh BASE_COMMIT NEW_COMMIT BENCH FILTER [ROUNDS]
#   tools/ab_bench.sh 3fdea31 HEAD geodesic 'geodesic_query/' 2
#   tools/ab_bench.sh 3fdea31 HEAD param 'param_iteration/(sd|arap|asap)/camelhead' 3
#   tools/ab_bench.sh 3fdea31 HEAD frame '^(warm_frame_one_way/|factorization/f64/)' 4
#
# Each commit is checked out in a worktree under target/ab/<commit>/src, with a link to this
# repository's `../shared` beside it (the benches read `../shared/data`), and its bench binary
# built there with the bench profile (fat LTO: several minutes each the first time). Extra criterion options can be
# given in CRITERION_ARGS (default: --sample-size 20 --measurement-time 5).
set -euo pipefail
if [ $# -lt 4 ]; then
    sed -n '2,14p' "$0"
    exit 2
fi
base=$1 new=$2 bench=$3 filter=$4 rounds=${5:-3}
args=${CRITERION_ARGS:---sample-size 20 --measurement-time 5}
root=$(git rev-parse --show-toplevel)
out="$root/target/ab"
mkdir -p "$out"

# The bench binary of a commit, built once per commit.
binary() {
    local commit dir
    commit=$(git -C "$root" rev-parse --short "$1")
    dir="$out/$commit"
    if [ ! -x "$dir/$bench" ]; then
        if [ ! -d "$dir/src" ]; then
            git -C "$root" worktree add --detach "$dir/src" "$commit" >&2
        fi
        if [ -d "$root/../shared" ] && [ ! -e "$dir/shared" ]; then
            ln -s "$(cd "$root/../shared" && pwd)" "$dir/shared"
        fi
        (cd "$dir/src" && CARGO_TARGET_DIR="$dir/target" cargo bench --bench "$bench" --no-run >&2)
        local built
        built=$(ls -t "$dir/target/release/deps/$bench"-* | grep -v '\.d$' | head -n 1)
        cp "$built" "$dir/$bench"
    fi
    echo "$dir"
}

a=$(binary "$base")
b=$(binary "$new")
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
for round in $(seq "$rounds"); do
    for side in "A $a" "B $b"; do
        set -- $side
        # Each side keeps its own criterion folder, so that neither compares with the other.
        echo "== $1 ($(basename "$2")) round $round"
        # shellcheck disable=SC2086
        (cd "$2" && "./$bench" --bench "$filter" $args 2>&1 |
            awk '/^[A-Za-z_]/ { name = $1 } /time: *\[/ { print "  " name ": " $(NF-3) " " $(NF-2) }')
    done
done
echo "load average: $(cut -d' ' -f1-3 /proc/loadavg)"
