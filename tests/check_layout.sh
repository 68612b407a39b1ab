#!/bin/sh
# The layout rules a compiler cannot check (docs/architecture.md), run by ctest from the source directory:
#   1. a component's private header (include/kergs/private/<c>impl.h) is included only by that component's own files,
#      so that no component reads another's fields;
#   2. the layers import only downward: a file (its layer is its folder under src/, or its header's component) includes
#      no header of a higher layer and, given the library's object files as arguments (ctest does), calls no function
#      defined in a higher layer's folder;
#   3. nothing in the repository points outside it (the project's documents live in docs/).
# Prints every violation and exits 1 if there is one.
# Usage: tests/check_layout.sh [object files of libkergs...]
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

# rule 2: layers, lowest first. The order is the one of the includes and calls today, which differs from a step's data
# flow (docs/architecture.md) in two places:
# - detect is below partition: the partition runs first in a step, but it moves the contacts with their disks
#   (KergsContactsMigrate) and weighs the grain graph by them (KergsContactIsActive);
# - io is below step: the stepper writes the results, the checkpoints and the samples and reads FCLib problems, while
#   io reads the scene, the contacts, the operators and the partition's state and calls nothing of the stepper. The
#   solvers and the partition stay below io: they return their figures in structs (src/step/statistics.c records them).
# main is src/main.c, the executable over everything.
LAYERS="base scene detect partition operators solver io step main"
layer_rank() {
  i=0
  for l in $LAYERS; do
    [ "$l" = "$1" ] && echo $i && return
    i=$((i + 1))
  done
  echo -1
}
# the layer of a header of include/kergs/ (private/ included), by the component that implements it
header_layer() {
  case "$1" in
    base.h | version.h | h5probe.h) echo base ;;
    scene.h | sceneimpl.h) echo scene ;;
    detect.h | detectimpl.h) echo detect ;;
    partition.h | partitionimpl.h) echo partition ;;
    operators.h | operatorsimpl.h) echo operators ;;
    law.h | sweep.h | sweepimpl.h | kernel.h | kernelimpl.h | predictor.h | predictorimpl.h | solver.h | solverimpl.h) echo solver ;;
    results.h | resultsimpl.h | xdmf.h | files.h | sample.h | fclib.h | checkpoint.h) echo io ;;
    stepper.h | stepperimpl.h) echo step ;;
    kergs.h) echo main ;;
    *) echo unknown ;;
  esac
}
# the layer of a file of src/ or include/kergs/
file_layer() {
  case "$1" in
    src/main.c) echo main ;;
    src/*/*) echo "$1" | cut -d/ -f2 ;;
    include/kergs/*) header_layer "$(basename "$1")" ;;
    *) echo unknown ;;
  esac
}
for f in $(find src include -name '*.c' -o -name '*.h'); do
  fl=$(file_layer "$f")
  fr=$(layer_rank "$fl")
  if [ "$fr" -lt 0 ]; then
    fail "$f belongs to no layer: place it in a component's folder, or name its header in header_layer (tests/check_layout.sh)"
    continue
  fi
  for h in $(sed -n 's|^#include [<"]kergs/\(private/\)\{0,1\}\([a-z_]*\.h\)[>"].*|\2|p' "$f"); do
    hl=$(header_layer "$h")
    hr=$(layer_rank "$hl")
    if [ "$hr" -lt 0 ]; then
      fail "$f includes kergs/$h, which belongs to no layer: name it in header_layer (tests/check_layout.sh)"
    elif [ "$hr" -gt "$fr" ]; then
      fail "$f ($fl) includes kergs/$h of the higher layer $hl (layers, lowest first: $LAYERS)"
    fi
  done
done
# the calls, from the symbols of the object files (folder of the source: .../src/<layer>/<file>.c.o)
object_layer() {
  case "$1" in
    */src/main.c.o) echo main ;;
    */src/*/*) echo "${1##*/src/}" | cut -d/ -f1 ;;
    *) echo unknown ;;
  esac
}
if [ $# -gt 0 ]; then
  symbols=$(mktemp) || exit 2
  trap 'rm -f "$symbols"' EXIT
  for o in "$@"; do
    ol=$(object_layer "$o")
    syms=$(nm "$o") || { fail "nm cannot read the object file $o"; continue; }
    echo "$syms" | awk -v obj="${o##*/src/}" -v layer="$ol" -v rank="$(layer_rank "$ol")" \
      '$1 == "U" { print "U", $2, obj, layer, rank } NF == 3 && $2 ~ /^[TDBRC]$/ { print "D", $3, obj, layer, rank }'
  done >"$symbols"
  calls=$(awk '$1 == "D" { def[$2] = $3 " (" $4 ")"; rank[$2] = $5 }
               $1 == "U" { use[NR] = $0 }
               END { for (k in use) { split(use[k], u, " "); s = u[2]
                       if ((s in rank) && (u[5] < 0 || rank[s] > u[5])) print u[3] " (" u[4] ") calls " s " of " def[s] } }' "$symbols" | sort)
  [ -z "$calls" ] || fail "calls up the layers (layers, lowest first: $LAYERS):
$calls"
fi

# rule 3: self-contained
hits=$(git grep -nI -e '\.\./shared' -e 'DESIGN\.md' -e 'TOOLCHAIN\.md' -- . ':!tests/check_layout.sh' 2>/dev/null)
[ -z "$hits" ] || fail "references outside the repository:
$hits"

[ $status = 0 ] && echo "layout: every rule holds"
exit $status
