#!/usr/bin/env bash
# Do two cellsim binaries write the same outputs? Runs one fixed set of commands with each
# (the paper's scenes, the axisymmetric flat scene, the coarse 3-D flat and push-pull
# scenes, a sweep, a study) and compares every CSV, PNG and markdown file they write, byte
# for byte (summary.json and timings.md hold wall times and are left out). For a change
# that should move no number: a restructuring, a renaming.
#
#   scripts/same-outputs.sh OLD_BINARY NEW_BINARY [WORK_DIR]
#
# e.g. (the binary of the commit before a change, built from a worktree):
#   git worktree add /tmp/before HEAD~1 && (cd /tmp/before && cargo build --release)
#   scripts/same-outputs.sh /tmp/before/target/release/cellsim target/release/cellsim
#
# About 8 minutes per binary on 2 cores (the coarse 3-D push-pull is most of it). Exit
# status 0 when every file is the same, 1 when one differs or is missing.
set -euo pipefail
cd "$(dirname "$0")/.."
[ $# -ge 2 ] || { echo "usage: $0 OLD_BINARY NEW_BINARY [WORK_DIR]" >&2; exit 2; }
old=$(realpath "$1"); new=$(realpath "$2")
work=${3:-$(mktemp -d /tmp/cellsim-same-outputs.XXXXXX)}
export OPENBLAS_NUM_THREADS=1

suite() {
  local bin=$1 out=$2
  mkdir -p "$out"
  "$bin" paper --out "$out/paper" --jobs 2 >/dev/null
  "$bin" run cases/3d/flat-axisym.ron --out "$out/axisym" --quiet >/dev/null
  "$bin" run cases/fast/flat-3d-coarse.ron --out "$out/flat-3d" --quiet >/dev/null
  "$bin" run cases/fast/push-pull-3d-coarse.ron --out "$out/push-pull-3d" --quiet >/dev/null
  "$bin" plot "$out/push-pull-3d" >/dev/null
  "$bin" sweep cases/sweeps/fast-flat.ron --out "$out/sweep" --jobs 2 --quiet >/dev/null || true
  "$bin" study cases/fast/push-pull-short-drag.ron --out "$out/study" --dt-max 0.5 --rungs 2 \
    --rtols 5e-3,1e-3 --ref-rtol 1e-6 --quiet >/dev/null
}

for side in old new; do
  bin=$old; [ "$side" = new ] && bin=$new
  echo "running the suite with $bin into $work/$side"
  rm -rf "${work:?}/$side"
  suite "$bin" "$work/$side"
done

# Wall times differ from run to run: the CSV columns named wall…, and the study's
# work-precision figure (wall time on its x axis), are left out of the comparison.
python3 - "$work" <<'PY'
import csv, io, os, sys
work = sys.argv[1]
def files(side):
    root = os.path.join(work, side)
    out = set()
    for d, _, fs in os.walk(root):
        for f in fs:
            if f.endswith(('.csv', '.png', '.md')) and f not in ('timings.md', 'work-precision.png'):
                out.add(os.path.relpath(os.path.join(d, f), root))
    return out
def content(path):
    data = open(path, 'rb').read()
    if not path.endswith('.csv'):
        return data
    rows = list(csv.reader(io.StringIO(data.decode())))
    keep = [i for i, h in enumerate(rows[0]) if not h.startswith('wall')] if rows else []
    return [[r[i] for i in keep if i < len(r)] for r in rows]
old, new = files('old'), files('new')
bad = 0
for rel in sorted(old | new):
    if rel not in new: print('missing in new:', rel); bad += 1
    elif rel not in old: print('only in new:', rel); bad += 1
    elif content(os.path.join(work, 'old', rel)) != content(os.path.join(work, 'new', rel)):
        print('differs:', rel); bad += 1
print(f"{len(old | new)} files compared: {'all the same' if bad == 0 else f'{bad} differ'}")
sys.exit(1 if bad else 0)
PY
