/* kergs solver: solves the per-step problem W r - v = -v^d with the contact law (eq. 1, 2).
   Variants are types registered by name, chosen with -solver_type (like KSPType):
     nlgs     Algorithm 2 (plain NLGS on W)
     nlkergs  Algorithm 3 (NLKerGS-P) on an explicitly stored W~ = W + omega N N^T: small problems, verification
     nlgsjac  Algorithm 6 (NLGS-Jac): Gauss-Seidel on W, Jacobi on the dense part omega N N^T, never stored
   Options: -solver_max_it (paper: 150), -solver_tol, -solver_criterion quad|maxm|natural; the regularised types
   add -solver_omega, -solver_omega_factor, the kernel's (-kernel_*) and the predictor's (-predictor_*). */
#ifndef KERGS_SOLVER_H
#define KERGS_SOLVER_H

#include <kergs/operators.h>
#include <kergs/sweep.h>
#include <kergs/results.h>

typedef const char *KergsSolverType;
#define KERGS_SOLVER_NLGS    "nlgs"
#define KERGS_SOLVER_NLKERGS "nlkergs"
#define KERGS_SOLVER_NLGSJAC "nlgsjac"

typedef enum {
  KERGS_CRITERION_QUAD,
  KERGS_CRITERION_MAXM,
  KERGS_CRITERION_NATURAL
} KergsCriterion;
PETSC_EXTERN const char *const KergsCriteria[];

typedef struct {
  PetscInt  iterations;
  PetscBool converged;
  PetscReal criterion; /* value of the chosen criterion at exit */
  PetscReal residual;  /* natural-map residual recomputed from r at exit */
  PetscReal seconds;       /* whole solve: set-up, sweeps, final residual */
  PetscReal sweep_seconds; /* the sweeps alone */
  PetscReal compute_seconds; /* this rank's arithmetic in the sweeps (no waiting for messages or reductions) */
} KergsSolveStats;

typedef struct _p_KergsSolver *KergsSolver;
typedef struct {
  PetscErrorCode (*setfromoptions)(KergsSolver, PetscOptionItems *); /* called after the common options, outside their block (NULL items): a type opens its own */
  PetscErrorCode (*setup)(KergsSolver, KergsScene, KergsContacts, KergsOperators);
  PetscErrorCode (*solve)(KergsSolver, KergsScene, KergsContacts, KergsOperators, KergsSolveStats *);
  PetscErrorCode (*view)(KergsSolver, PetscViewer);
  PetscErrorCode (*destroy)(KergsSolver);
  /* optional: before every sweep, update the extra right-hand side from the current r (NLGS-Jac's Jacobi part) */
  PetscErrorCode (*presweep)(KergsSolver, KergsOperators, PetscReal *extra);
  /* optional: record the type's own statistics of the step */
  PetscErrorCode (*record)(KergsSolver, KergsResults);
} KergsSolverOps;

struct _p_KergsSolver {
  MPI_Comm       comm;
  char           type[64];
  KergsSolverOps ops;
  void          *data;
  PetscInt       max_it;
  PetscReal      tol;
  KergsCriterion criterion;
  KergsSweep     sweep;         /* Gauss-Seidel on W; also computes the physical residual */
  KergsSweep     iterate_sweep; /* when set, the sweeps run on this one instead (nlkergs: on W~) */
  PetscBool      needs_H;       /* the type reads H_f, H_g during its solve (kernel projector, predictors), and W over all
                                   pairs of contacts: the time step keeps H alive from assembly to the velocity update and
                                   assembles the whole W (otherwise W couples the active contacts only) */
  PetscReal     *mu;     /* per local contact */
  PetscBool     *active; /* per local contact */
  PetscInt       nalloc;
};

PETSC_EXTERN PetscErrorCode KergsSolverRegister(const char[], PetscErrorCode (*)(KergsSolver));
PETSC_EXTERN PetscErrorCode KergsSolverCreate(MPI_Comm, KergsSolver *);
PETSC_EXTERN PetscErrorCode KergsSolverSetType(KergsSolver, KergsSolverType);
PETSC_EXTERN PetscErrorCode KergsSolverSetFromOptions(KergsSolver);
PETSC_EXTERN PetscErrorCode KergsSolverSolve(KergsSolver, KergsScene, KergsContacts, KergsOperators, KergsSolveStats *);
PETSC_EXTERN PetscErrorCode KergsSolverView(KergsSolver, PetscViewer);
PETSC_EXTERN PetscErrorCode KergsSolverDestroy(KergsSolver *);
/* Shared by the types: mark active contacts (predicted gap <= 0) and set up the sweep on W. */
PETSC_EXTERN PetscErrorCode KergsSolverSetUpSweep(KergsSolver, KergsScene, KergsContacts, KergsOperators);
/* Shared by the types: run sweeps until the criterion or max_it, extra/diag as in KergsSweepRun; when the type
   has a presweep hook, extra (one entry per local component) is updated by it before every sweep. */
PETSC_EXTERN PetscErrorCode KergsSolverIterate(KergsSolver, KergsOperators, PetscReal *extra, const PetscReal *Wdiag, KergsSolveStats *);
/* Statistics of the step common to every type (sizes of H_f and W) and the type's own. */
PETSC_EXTERN PetscErrorCode KergsSolverRecordStats(KergsSolver, KergsOperators, KergsResults);

PETSC_EXTERN PetscErrorCode KergsSolverCreate_NLGS(KergsSolver);
PETSC_EXTERN PetscErrorCode KergsSolverCreate_NLKerGS(KergsSolver);
PETSC_EXTERN PetscErrorCode KergsSolverCreate_NLGSJac(KergsSolver);

#endif
