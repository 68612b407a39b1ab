/* kergs solver type "nlgs": Algorithm 2, plain non-linear Gauss-Seidel on W with the exact one-contact law,
   warm-started from the previous step's impulses. */
#include <kergs/private/solverimpl.h>

static PetscErrorCode SolverSetUp_NLGS(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  PetscFunctionBeginUser;
  PetscCall(KergsSolverSetUpSweep(s, scene, contacts, ops));
  PetscFunctionReturn(0);
}

static PetscErrorCode SolverSolve_NLGS(KergsSolver s, KergsScene scene, KergsContacts contacts, KergsOperators ops, KergsSolveStats *stats)
{
  PetscFunctionBeginUser;
  (void)scene;
  (void)contacts;
  PetscCall(KergsSolverIterate(s, ops, NULL, NULL, stats));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSolverCreate_NLGS(KergsSolver s)
{
  PetscFunctionBeginUser;
  s->ops.setup = SolverSetUp_NLGS;
  s->ops.solve = SolverSolve_NLGS;
  PetscFunctionReturn(0);
}
