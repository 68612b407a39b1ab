/* An example program over the kergs library, built against an installed tree (examples/CMakeLists.txt): it creates the
   scene, solver and time loop from the options database (-options_file cases/confine500.opts ...), takes two time steps
   and prints the number of contacts and how the solver did. It writes no file (it sets -output_none: the results file
   is opened by KergsStepperRun, the whole time loop, which this example replaces by its own calls to KergsStepperStep).

     mpiexec -n 2 kergs_contacts -options_file cases/confine500.opts [-steps_example N] */
static const char help[] = "kergs example: a scene from the options, a few time steps, the contact count.\n";

#include <kergs/kergs.h>

static PetscErrorCode Example(void)
{
  KergsStepper  stepper;
  KergsContacts contacts;
  KergsResults  results;
  PetscInt      nsteps = 2, ncontacts, step;
  PetscReal     time, iterations, residual;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsGetInt(NULL, NULL, "-steps_example", &nsteps, NULL));
  PetscCheck(nsteps >= 1, PETSC_COMM_WORLD, PETSC_ERR_ARG_OUTOFRANGE, "-steps_example must be >= 1, got %" PetscInt_FMT, nsteps);
  PetscCall(PetscOptionsSetValue(NULL, "-output_none", "true"));
  PetscCall(KergsStepperCreate(PETSC_COMM_WORLD, &stepper));
  PetscCall(KergsStepperSetFromOptions(stepper));
  for (PetscInt k = 0; k < nsteps; k++) PetscCall(KergsStepperStep(stepper));
  PetscCall(KergsStepperGetContacts(stepper, &contacts));
  PetscCall(KergsContactsGetGlobalRange(contacts, NULL, &ncontacts));
  PetscCall(KergsStepperGetResults(stepper, &results));
  PetscCall(KergsResultsGetStatistic(results, "step", -1, &time, NULL));
  step = (PetscInt)time;
  PetscCall(KergsResultsGetStatistic(results, "time", -1, &time, NULL));
  PetscCall(KergsResultsGetStatistic(results, "iterations", -1, &iterations, NULL));
  PetscCall(KergsResultsGetStatistic(results, "residual", -1, &residual, NULL));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "example: step %" PetscInt_FMT " time %.6f contacts %" PetscInt_FMT " sweeps %d residual %.3e\n",
                        step, (double)time, ncontacts, (int)iterations, (double)residual));
  PetscCall(KergsStepperDestroy(&stepper));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(Example());
  PetscCall(PetscFinalize());
  return 0;
}
