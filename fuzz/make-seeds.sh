#!/usr/bin/env bash
# Generates the seed corpora of the fuzz targets into OUT/<target>/ (default build-fuzz/fuzz-corpus/seeds):
# small subsets and truncations of ../shared/data, the scenes/ files and hand-written files
# (fuzz/make_seeds.py), and files written by MedSpring's own writers (medspring_fuzz_seeds from the
# build folder BUILD, default build-fuzz; skipped with a note when it is not built). The committed
# seeds of fuzz/seeds/<target>/ are used by fuzz/run directly and are not copied.
#   bash fuzz/make-seeds.sh [OUT] [BUILD]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
out=${1:-$root/build-fuzz/fuzz-corpus/seeds}
build=${2:-$root/build-fuzz}
rm -rf "$out"
mkdir -p "$out"
/usr/bin/python3 "$root/fuzz/make_seeds.py" "$out" --scenes "$root/scenes"
if [ -x "$build/fuzz/medspring_fuzz_seeds" ]; then
  # the seed writer is built with the sanitizers in a fuzz tree: leaks of VTK's singletons are not ours
  ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0} "$build/fuzz/medspring_fuzz_seeds" "$out"
  echo "make-seeds.sh: medspring_fuzz_seeds wrote $(find "$out" -name 'gen_*' | wc -l) files"
else
  echo "make-seeds.sh: $build/fuzz/medspring_fuzz_seeds not built: seeds of MedSpring's writers left out"
fi
