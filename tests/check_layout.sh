#!/bin/sh
# The layout rules a compiler cannot check (docs/architecture.md), run by ctest from the source directory:
#   1. a component's private header (include/kergs/private/<c>impl.h) is included only by that component's own files,
#      so that no component reads another's fields;
#   2. io stays at the end of a step's data flow: the solvers, the kernel, the predictors and the partition never
#      include the results writer (they return their figures in structs; src/step/statistics.c records them);
#   3. nothing in the repository points outside it (the project's documents live in docs/).
# Prints every violation and exits 1 if there is one.
cd "$(dirname "$0")/.." || exit 2
status=0
fail() { echo "layout: $*"; status=1; }

# rule 1: private header -> the files allowed to include it
allowed() {
  case "$1" in
    sceneimpl.h) echo "src/scene/" ;;
    detectimpl.h) echo "src/detect/" ;;
    operatorsimpl.h) echo "src/operators/" ;;
    sweepimpl.h) echo "src/solver/sweep.c" ;;
    kernelimpl.h) echo "src/solver/kernel.c" ;;
    predictorimpl.h) echo "src/solver/predictor.c src/solver/predictors/" ;;
    solverimpl.h) echo "src/solver/solver.c src/solver/monitor.c src/solver/solvers/" ;;
    partitionimpl.h) echo "src/partition/" ;;
    resultsimpl.h) echo "src/io/results.c" ;;
    stepperimpl.h) echo "src/step/" ;;
    *) echo "" ;;
  esac
}
for f in $(find src include -name '*.c' -o -name '*.h'); do
  for h in $(sed -n 's|^#include [<"]kergs/private/\([a-z]*impl\.h\)[>"].*|\1|p' "$f"); do
    ok=0
    for prefix in $(allowed "$h"); do
      case "$f" in "$prefix"*) ok=1 ;; esac
    done
    case "$f" in include/kergs/private/"$h") ok=1 ;; esac
    # a private header may build on the public header of its own component only
    [ $ok = 1 ] || fail "$f includes kergs/private/$h, private to $(allowed "$h")"
  done
done

# rule 2: no results writer below the stepper
for f in $(find src/solver src/partition -name '*.c' -o -name '*.h'); do
  if grep -Eq '^#include [<"]kergs/(results|kergs)\.h[>"]' "$f"; then fail "$f includes the results writer (io belongs at the end: return figures in a struct)"; fi
done

# rule 3: self-contained
hits=$(git grep -nI -e '\.\./shared' -e 'DESIGN\.md' -e 'TOOLCHAIN\.md' -- . ':!tests/check_layout.sh' 2>/dev/null)
[ -z "$hits" ] || fail "references outside the repository:
$hits"

[ $status = 0 ] && echo "layout: every rule holds"
exit $status
