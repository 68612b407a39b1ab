# kergs: shared by scripts/run, scripts/test and scripts/bench (sourced, not run).
# Installs the Debian packages kergs needs (only those missing), configures and builds in build/.
set -euo pipefail
KERGS_ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
KERGS_BUILD=${KERGS_BUILD:-$KERGS_ROOT/build}
KERGS_PACKAGES="petsc-dev libmetis-dev libhdf5-openmpi-dev openmpi-bin cmake pkg-config make gcc libopenblas0-pthread
  libfclib-dev python3-h5py python3-matplotlib python3-numpy python3-scipy python3-siconos valgrind"
KERGS_PACKAGES="$KERGS_PACKAGES clang-format" # tests/check_format.sh
# tests/check_xdmf.py, scripts/render_xdmf.py: VTK's XDMF readers and offscreen rendering. Debian's python3-vtk9 is built
# without the XDMF readers; python3-paraview ships a VTK that has them (it replaces python3-vtk9).
KERGS_PACKAGES="$KERGS_PACKAGES python3-paraview xvfb xauth" # xvfb-run: rendering without a display
KERGS_PACKAGES="$KERGS_PACKAGES lammps" # scripts/dem_compare: the soft-contact DEM it compares kergs with (lmp, GRANULAR)

kergs_install() {
  local missing=""
  for p in $KERGS_PACKAGES; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing="$missing $p"
  done
  [ -z "$missing" ] && return 0
  echo "kergs: installing$missing"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get update -qq
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $missing >/dev/null
}

kergs_build() {
  if [ ! -f "$KERGS_BUILD/CMakeCache.txt" ]; then
    cmake -S "$KERGS_ROOT" -B "$KERGS_BUILD" -DCMAKE_BUILD_TYPE=Release -DKERGS_WERROR=ON >/dev/null
  fi
  cmake --build "$KERGS_BUILD" -j "$(nproc)" -- --no-print-directory | grep -E "warning|error|Error" || true
  test -x "$KERGS_BUILD/kergs"
}

# Open MPI refuses root and more ranks than cores unless told; MPICH ignores these.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
export OMPI_MCA_btl_vader_single_copy_mechanism=none OPENBLAS_NUM_THREADS=1
