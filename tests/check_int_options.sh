#!/bin/sh
# Every integer option of the solver types (src/solver/, read with PetscOptionsInt) is in the stepper's list of options
# checked for 32-bit overflow (src/step/stepper.c, CheckSolverIntegerOptions): a new one left out would wrap silently.
cd "$(dirname "$0")/.." || exit 2
status=0
for opt in $(grep -rhoE 'PetscOptionsInt\("-[a-z_]+"' src/solver | sed 's/PetscOptionsInt("//; s/"$//' | sort -u); do
  grep -q "\"$opt\"" src/step/stepper.c || { echo "int options: $opt (src/solver/) is not checked by CheckSolverIntegerOptions in src/step/stepper.c"; status=1; }
done
[ $status = 0 ] && echo "int options: every integer option of the solver types is checked for overflow"
exit $status
