/* Solver type "tresca" (src/solver/solvers/tresca.c): one-contact cases (open, stick, slip on a slope) solved to 1e-10
   with the right physics, and frictionless confine500 solved in one Tresca iteration (one QP: the thresholds do not
   matter) with the velocities of the newton type. The infeasible straight row is a ctest of test_regularised.c
   (tests/tresca.cmake). */
static const char help[] = "kergs tresca solver tests.\n";

#include "testing.h"
#include <string.h>

/* The one-contact cases of testing.h (open, stick, stick and slip on a slope) to 1e-10 with the right physics. */
static PetscErrorCode TestOneContact(const char *tao)
{
  char solver[256];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(solver, sizeof(solver), "-solver_type tresca -solver_tol 1e-10 -solver_tresca_tao_type %s", tao));
  PetscCall(CheckOneContactCases(solver, tao));
  PetscFunctionReturn(0);
}

/* Frictionless confine500, 2 steps: without friction the thresholds do not matter, one QP is the whole problem, so
   each step takes one Tresca iteration; and the velocities are newton's. */
static PetscErrorCode TestFrictionless(const char *tao)
{
  KergsStepper a, b;
  PetscInt     maxits, nconv, itsb, nconvb;
  PetscReal    maxres, resb, diff = 0, scale = 0;
  char         opts[1024];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(opts, sizeof(opts),
                          "-options_file cases/confine500.opts -friction 0 -steps 2 -solver_type tresca -solver_tol 1e-10 "
                          "-solver_tresca_tao_type %s",
                          tao));
  PetscCall(RunSteps(opts, 2, &a, &maxits, &maxres, &nconv));
  PetscCall(
      Checkf((PetscBool)(nconv == 2 && maxres <= 1e-10), maxres, 1e-10, "frictionless confine500, %s: 2 steps converged (residual)", tao));
  PetscCall(Checkf((PetscBool)(maxits == 1), maxits, 1, "frictionless confine500, %s: one Tresca iteration per step", tao));
  PetscCall(RunSteps("-options_file cases/confine500.opts -friction 0 -steps 2 -solver_type newton -solver_tol 1e-12", 2, &b, &itsb, &resb,
                     &nconvb));
  PetscCall(VelocityDifference(a, b, &diff, &scale));
  PetscCall(Checkf((PetscBool)(nconvb == 2 && diff <= 1e-7 * scale), diff / scale, 1e-7,
                   "frictionless confine500, %s: velocities = newton's (relative)", tao));
  PetscCall(KergsStepperDestroy(&a));
  PetscCall(KergsStepperDestroy(&b));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  char tao[64] = "tron";

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  PetscCall(PetscOptionsGetString(NULL, NULL, "-test_tao_type", tao, sizeof(tao), NULL)); /* before MakeStepper clears them */
  PetscCall(TestOneContact(tao));
  /* blmvm (quasi-Newton) needs thousands of iterations for confine500's frictionless QP to 1e-10: tron only */
  if (!strcmp(tao, "tron")) PetscCall(TestFrictionless(tao));
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
