/* kergs: what the kernel-regularised solver types (nlkergs, nlgsjac) share: the kernel projector, the
   predictor r~, omega, z~ = Z r~ (Algorithm 3 and 6). Private to src/solver/solvers/. */
#ifndef KERGS_REGULARISED_H
#define KERGS_REGULARISED_H

#include <kergs/private/solverimpl.h>
#include <kergs/kernel.h>
#include <kergs/predictor.h>

typedef struct {
  KergsKernel    kernel;
  KergsPredictor predictor;
  PetscReal      omega_fixed;  /* -solver_omega: absolute omega (0: automatic) */
  PetscReal      omega_factor; /* -solver_omega_factor: omega = factor * ||W||_2 (the paper: 1/20) */
  PetscInt       power_its;    /* -solver_omega_power_its: power iterations estimating ||W||_2 */
  PetscReal      omega, normW;
  Vec            rtilde, ztilde, z; /* r~, Z r~, Z r (work) */
  PetscReal     *extra, *Wdiag;     /* per local component: extra right-hand side; per local contact: blocks of W~ */
  PetscInt       nalloc;
  PetscReal      predict_seconds;
} KergsRegularised;

PETSC_INTERN PetscErrorCode KergsRegularisedCreate(MPI_Comm, KergsRegularised **);
PETSC_INTERN PetscErrorCode KergsRegularisedSetFromOptions(PetscOptionItems *, KergsSolver, KergsRegularised *);
/* Active contacts and the sweep on W, omega, the kernel of this step's H_f, r~ and z~ = Z r~. */
PETSC_INTERN PetscErrorCode KergsRegularisedSetUp(KergsSolver, KergsRegularised *, KergsScene, KergsContacts, KergsOperators);
/* omega, ||W||_2, the predictor's type and cost, and the kernel's figures of the step */
PETSC_INTERN PetscErrorCode KergsRegularisedStats(KergsRegularised *, KergsSolveStats *);
PETSC_INTERN PetscErrorCode KergsRegularisedView(KergsRegularised *, PetscViewer);
PETSC_INTERN PetscErrorCode KergsRegularisedDestroy(KergsRegularised **);

#endif
