/* Solver type "snesvi" (src/solver/solvers/snesvi.c, PETSc's SNESVI on the law written as a complementarity problem):
   one-contact cases (open, stick, stick and slip on a slope) solved to 1e-10 with the right physics, and frictionless
   confine500 (the linear complementarity problem of the normal impulses, W singular) solved to 1e-10 with the
   velocities of the newton type. Run for the SNESVI type given by -test_snes_type (tests/snesvi.cmake). */
static const char help[] = "kergs snesvi solver tests.\n";

#include "testing.h"

/* The one-contact cases of testing.h (open, stick, stick and slip on a slope) to 1e-10 with the right physics. */
static PetscErrorCode TestOneContact(const char *type)
{
  char solver[256];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(solver, sizeof(solver), "-solver_type snesvi -solver_tol 1e-10 -solver_snes_type %s", type));
  PetscCall(CheckOneContactCases(solver, type));
  PetscFunctionReturn(0);
}

/* Frictionless confine500, 2 steps: the MCP is the linear complementarity problem of the normal impulses, W singular;
   solved to 1e-10 in at most 20 SNES iterations a step (5-15 measured), with newton's velocities (unique without
   friction, whatever the kernel part of r). */
static PetscErrorCode TestFrictionless(const char *type)
{
  KergsStepper a, b;
  PetscInt     maxits, nconv, itsb, nconvb;
  PetscReal    maxres, resb, diff = 0, scale = 0;
  char         opts[1024];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(
      opts, sizeof(opts),
      "-options_file cases/confine500.opts -friction 0 -steps 2 -solver_type snesvi -solver_tol 1e-10 -solver_snes_type %s", type));
  PetscCall(RunSteps(opts, 2, &a, &maxits, &maxres, &nconv));
  PetscCall(
      Checkf((PetscBool)(nconv == 2 && maxres <= 1e-10), maxres, 1e-10, "frictionless confine500, %s: 2 steps converged (residual)", type));
  PetscCall(Checkf((PetscBool)(maxits <= 20), maxits, 20, "frictionless confine500, %s: at most 20 SNES iterations a step", type));
  PetscCall(RunSteps("-options_file cases/confine500.opts -friction 0 -steps 2 -solver_type newton -solver_tol 1e-12", 2, &b, &itsb, &resb,
                     &nconvb));
  PetscCall(VelocityDifference(a, b, &diff, &scale));
  PetscCall(Checkf((PetscBool)(nconvb == 2 && diff <= 1e-7 * scale), diff / scale, 1e-7,
                   "frictionless confine500, %s: velocities = newton's (relative)", type));
  PetscCall(KergsStepperDestroy(&a));
  PetscCall(KergsStepperDestroy(&b));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  char type[64] = "vinewtonrsls";

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsInitializePackage());
  PetscCall(PetscOptionsGetString(NULL, NULL, "-test_snes_type", type, sizeof(type), NULL)); /* before MakeStepper clears them */
  PetscCall(TestOneContact(type));
  PetscCall(TestFrictionless(type));
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
