#!/usr/bin/env bash
# Memory check of the cell model under valgrind memcheck: short runs through IDA with every
# C library behind the FFI (SuiteSparse's KLU on METIS's ordering, and UMFPACK refined and, on
# the condensed system, on METIS's ordering unrefined), covering
# the fall, the landing and the inertia switch (cases/fast/flat-gravity.ron to t = 10.5 s).
# With --all, also faer's LU, KLU on its own ordering, the condensed faer LU and a run on
# micropillars with adhesion and both active regions (cases/fast/push-pull-short.ron to
# t = 110 s): about 15 min of CPU instead of 6.
# Fails unless every run reports "definitely lost: 0 bytes" and no memory error.
#
# scripts/valgrind.supp holds the one suppression needed, with its reason.
set -euo pipefail
cd "$(dirname "$0")/.."

if ! command -v valgrind >/dev/null; then
    sudo=""; [ "$(id -u)" = 0 ] || sudo=sudo
    $sudo apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends valgrind
fi
cargo build --release --quiet
cargo build --release --quiet --example robertson

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
sed 's/t_end: 200.0,/t_end: 10.5,/' cases/fast/flat-gravity.ron > "$tmp/fall.ron"
sed 's/t_end: 600.0,/t_end: 110.0,/' cases/fast/push-pull-short.ron > "$tmp/pillars.ron"
grep -q 't_end: 10.5' "$tmp/fall.ron" && grep -q 't_end: 110.0' "$tmp/pillars.ron"

runs="fall:klu-metis fall:umfpack fall:umfpack-condensed"
if [ "${1:-}" = "--all" ]; then
    runs="$runs fall:faer fall:klu fall:faer-condensed pillars:faer"
fi
# The runs are independent: two at a time (the machines here have two cores).
check() {
    local case_name=${1%%:*} solver=${1#*:}
    local log="$tmp/$case_name-$solver.log"
    # One thread per run: valgrind runs threads one at a time, and the element loops' thread
    # pool is safe Rust (the C libraries are what this checks); two runs go side by side.
    if RAYON_NUM_THREADS=1 valgrind --leak-check=full --errors-for-leak-kinds=definite --error-exitcode=3 \
        --suppressions=scripts/valgrind.supp \
        target/release/cellsim run "$tmp/$case_name.ron" --out "$tmp/out-$case_name-$solver" \
        --quiet --linear-solver "$solver" >/dev/null 2>"$log"; then
        echo "memcheck: $case_name ($solver): $(grep -o 'definitely lost: .*' "$log"); $(grep -o 'ERROR SUMMARY: [0-9]* errors' "$log")"
    else
        echo "memcheck: $case_name with $solver FAILED:"
        cat "$log"
        return 1
    fi
}
status=0
pids=()
for run in $runs; do
    check "$run" &
    pids+=($!)
    if [ ${#pids[@]} -ge 2 ]; then
        wait "${pids[0]}" || status=1
        pids=("${pids[@]:1}")
    fi
done
for pid in "${pids[@]}"; do
    wait "$pid" || status=1
done
# IDA's root finding (IDARootInit and its callback): SUNDIALS' Robertson example with its
# root functions, the only run here that has any.
log="$tmp/robertson-roots.log"
if valgrind --leak-check=full --errors-for-leak-kinds=definite --error-exitcode=3 \
    --suppressions=scripts/valgrind.supp \
    target/release/examples/robertson --roots >/dev/null 2>"$log"; then
    echo "memcheck: robertson --roots: $(grep -o 'definitely lost: .*' "$log"); $(grep -o 'ERROR SUMMARY: [0-9]* errors' "$log")"
else
    echo "memcheck: robertson --roots FAILED:"
    cat "$log"
    status=1
fi
exit $status
