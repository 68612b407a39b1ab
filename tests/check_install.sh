#!/usr/bin/env bash
# Usage: check_install.sh BUILD_DIR WORK_DIR MPIEXEC   (run from the source tree)
# The installed tree works for another program (docs/running.md, "Installing"):
#   - cmake --install BUILD_DIR --prefix WORK_DIR/prefix installs libkergs, the public headers (none of
#     include/kergs/private), the kergs executable and the CMake package (config, version file, exported targets);
#   - the tree is moved elsewhere (it must not depend on where it was installed), then examples/ is configured with
#     find_package(kergs 0.1) against it, built and run on 2 ranks: 2 steps of confine500 give the contact count, the
#     sweeps and the residual that the installed kergs executable records for the same 2 steps;
#   - find_package(kergs 99) is refused by the version file.
set -uo pipefail
build=$1 work=$2 mpiexec=$3
fail=0
check() { # check CONDITION-STATUS WHAT
  if [ "$1" -eq 0 ]; then echo "ok   $2"; else echo "FAIL $2"; fail=1; fi
}
rm -rf "$work" && mkdir -p "$work"
work=$(cd "$work" && pwd)

cmake --install "$build" --prefix "$work/installed" > "$work/install.log" 2>&1
check $? "cmake --install $build --prefix $work/installed"
mv "$work/installed" "$work/prefix" # relocated: nothing may point to the install path
p=$work/prefix
missing=""
for f in bin/kergs lib/libkergs.a include/kergs/kergs.h include/kergs/stepper.h include/kergs/xdmf.h \
  lib/cmake/kergs/kergsConfig.cmake lib/cmake/kergs/kergsConfigVersion.cmake lib/cmake/kergs/kergsTargets.cmake; do
  [ -f "$p/$f" ] || missing="$missing $f"
done
check $([ -z "$missing" ]; echo $?) "installed: the executable, the library, the public headers, the CMake package${missing:+ (missing:$missing)}"
private=$(find "$p" -name '*impl.h' -o -name private | head -3)
check $([ -z "$private" ]; echo $?) "no private header installed${private:+ ($private)}"
headers=$(ls include/kergs/*.h | wc -l)
installed=$(ls "$p"/include/kergs/*.h | wc -l)
check $([ "$headers" -eq "$installed" ]; echo $?) "every public header: $installed of $headers"
leaks=$(grep -l "$work/installed" -r "$p" 2>/dev/null | head -3)
check $([ -z "$leaks" ]; echo $?) "no installed file names the install path${leaks:+ ($leaks)}"

cmake -S examples -B "$work/example" -DCMAKE_PREFIX_PATH="$p" -DCMAKE_BUILD_TYPE=Release -DCMAKE_C_FLAGS="-Wall -Wextra -Werror" > "$work/example-configure.log" 2>&1 &&
  cmake --build "$work/example" > "$work/example-build.log" 2>&1
check $? "examples/ configured with find_package(kergs 0.1) against the moved tree and built (-Wall -Wextra -Werror)"
out=$("$mpiexec" -n 2 "$work/example/kergs_contacts" -options_file cases/confine500.opts -quiet 2>&1)
rc=$?
echo "$out" | tail -n 3
line=$(echo "$out" | grep '^example: ')
check $([ $rc -eq 0 ] && [ -n "$line" ]; echo $?) "the example ran 2 steps of confine500 on 2 ranks"

"$mpiexec" -n 2 "$p/bin/kergs" -options_file cases/confine500.opts -steps 2 -output "$work/run.h5" -quiet > "$work/run.log" 2>&1
check $? "the installed kergs ran the same 2 steps"
want=$(/usr/bin/python3 -c "
import h5py
f = h5py.File('$work/run.h5', 'r')
s = f['stats']
print('example: step %d time %.6f contacts %d sweeps %d residual %.3e' % (s['step'][-1], s['time'][-1], s['contacts'][-1],
      s['iterations'][-1], s['residual'][-1]))")
echo "expected: $want"
check $([ "$line" = "$want" ]; echo $?) "the example's step, time, contact count, sweeps and residual are the executable's"

cmake -S examples -B "$work/too-new" -DCMAKE_PREFIX_PATH="$p" -DKERGS_MIN_VERSION=99 > "$work/too-new.log" 2>&1
rc=$?
check $([ $rc -ne 0 ] && grep -qi "version" "$work/too-new.log"; echo $?) "find_package(kergs 99) is refused (the version file)"
exit $fail
