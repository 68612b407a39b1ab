/* kergs solver, private: the solver object and its operations, for src/solver/solver.c, monitor.c and the types in
   src/solver/solvers/ (as PETSc's KSP types use kspimpl.h); other components go through kergs/solver.h. */
#ifndef KERGS_SOLVERIMPL_H
#define KERGS_SOLVERIMPL_H

#include <kergs/solver.h>
#include <kergs/sweep.h>
#include <petsctao.h>

#define KERGS_SOLVER_MAXMONITORS 5

typedef struct {
  PetscErrorCode (*setfromoptions)(PetscOptionItems *, KergsSolver); /* inside the solver's options block, as PETSc's types */
  PetscErrorCode (*setup)(KergsSolver, KergsScene, KergsContacts, KergsOperators);
  PetscErrorCode (*solve)(KergsSolver, KergsScene, KergsContacts, KergsOperators, KergsSolveStats *);
  PetscErrorCode (*view)(KergsSolver, PetscViewer);
  PetscErrorCode (*destroy)(KergsSolver);
  /* optional: before every sweep, update the extra right-hand side from the current r (NLGS-Jac's Jacobi part) */
  PetscErrorCode (*presweep)(KergsSolver, KergsOperators, PetscReal *extra);
  /* optional: add the type's own figures of the step to its statistics (KergsSolveStatsAdd) */
  PetscErrorCode (*stats)(KergsSolver, KergsSolveStats *);
} KergsSolverOps;

struct _p_KergsSolver {
  MPI_Comm       comm;
  char           type[64];
  char          *prefix; /* options prefix (KergsSolverSetOptionsPrefix), prepended to every option of the solver */
  KergsSolverOps ops;
  void          *data;
  PetscInt       max_it;
  PetscReal      tol;
  PetscReal      residual_tol;     /* -solver_residual_tol: largest natural residual of the original problem of a converged step */
  PetscReal      velocity_tol;     /* -solver_velocity_tol: largest relative velocity error of a converged step */
  PetscReal      infeasible_ratio; /* -solver_infeasible_ratio (DetectInfeasible) */
  PetscReal     *infeasible;       /* per local contact, the weight of the certificate's network (NULL: none) */
  KergsCriterion criterion;
  PetscBool      fixed_criterion; /* the type decides convergence by the natural residual whatever -solver_criterion */
  const char    *iteration_name;  /* what -solver_max_it counts: "sweeps" or "Newton steps" */
  KergsSweep     sweep;           /* Gauss-Seidel on W; also computes the physical residual */
  KergsSweep     iterate_sweep;   /* when set, the sweeps run on this one instead (nlkergs: on W~) */
  PetscBool      needs_H;         /* the type reads H_f, H_g during its solve (kernel projector, predictors): the time step
                                     keeps H alive from assembly to the velocity update */
  PetscBool needs_full_W;         /* the type works on W over all pairs of potential contacts (the kernel-regularised
                                     types); otherwise W couples the active contacts only */
  PetscBool needs_both_triangles; /* the type reads W with both triangles (KergsOperatorsGetFullW) */
  /* monitors (KergsSolverMonitorSet); the last iteration's call is held back until the solve's exit, so that its residual
     is the one recorded (KergsSolverMonitor) */
  KergsSolverMonitorFn monitor[KERGS_SOLVER_MAXMONITORS];
  void                *monitorctx[KERGS_SOLVER_MAXMONITORS];
  PetscErrorCode (*monitordestroy[KERGS_SOLVER_MAXMONITORS])(void **);
  PetscInt          nmonitors;
  PetscBool         monitor_options; /* -solver_monitor's monitor is set */
  PetscViewer       reason_viewer;   /* -solver_converged_reason */
  PetscViewerFormat reason_format;
  PetscInt          step; /* KergsSolverSetStepNumber */
  PetscLogDouble    solve_start;
  PetscBool         held; /* an iteration's monitor call is held back */
  PetscInt          held_it;
  PetscReal         held_criterion, held_residual, held_seconds;
  PetscReal        *mu;         /* per local contact */
  PetscBool        *active;     /* per local contact */
  PetscReal        *gapvel;     /* per local contact: the gap rule's normal velocity offset added to v^d (predictive) */
  PetscInt64        shifted_id; /* the v^d (its object id) that already holds them: a second set-up on the same problem
                                   does not add them twice */
  PetscInt nalloc;
};

/* Shared by the types: mark active contacts (predicted gap <= 0) and set up the sweep on W. */
PETSC_INTERN PetscErrorCode KergsSolverSetUpSweep(KergsSolver, KergsScene, KergsContacts, KergsOperators);
/* Shared by the types that work on the active contacts only: their components (IS) and W over them (AIJ). */
PETSC_INTERN PetscErrorCode KergsSolverActiveSubmatrix(KergsSolver, Mat W, PetscInt n, PetscInt nc, IS *is, Mat *Wa);
/* Shared by the types: run sweeps until the criterion or max_it, extra/diag as in KergsSweepRun; when the type
   has a presweep hook, extra (one entry per local component) is updated by it before every sweep. */
PETSC_INTERN PetscErrorCode KergsSolverIterate(KergsSolver, KergsOperators, PetscReal *extra, const PetscReal *Wdiag, KergsSolveStats *);
/* For the types: the criterion fell below -solver_tol; sets stats->reason to the criterion's CONVERGED_ value. */
PETSC_INTERN PetscErrorCode KergsSolverCriterionMet(KergsSolver, KergsSolveStats *);
/* For the types: the options prefix of an inner object (kernel, predictor, KSP, SNES, Tao): the solver's prefix then inner */
PETSC_INTERN PetscErrorCode KergsSolverInnerPrefix(KergsSolver, const char inner[], char prefix[], size_t len);
/* For the types: iteration `it` of the solve ended with the type's criterion at `criterion` and the natural residual of
   the original problem at `residual` (NaN when the type did not compute it). Nothing when no monitor is set. */
PETSC_INTERN PetscErrorCode KergsSolverMonitor(KergsSolver, PetscInt it, PetscReal criterion, PetscReal residual);
/* At the solve's exit: the last iteration's monitor call, with the residual recorded for the step (src/solver/monitor.c) */
PETSC_INTERN PetscErrorCode KergsSolverMonitorFlush(KergsSolver, PetscReal residual);
PETSC_INTERN PetscErrorCode KergsSolverMonitorSetFromOptions(PetscOptionItems *, KergsSolver);
/* For the types that hand a convex QP min 1/2 x^T H x + c^T x to a Tao (src/solver/solvers/quadratic.c): its objective,
   gradient and constant Hessian, read from *q at every call (H and c may change between solves, not their layout). */
typedef struct {
  Mat H;
  Vec c;
} KergsQuadratic;
PETSC_INTERN PetscErrorCode KergsQuadraticSetTao(KergsQuadratic *, Tao);
PETSC_INTERN PetscErrorCode KergsSolverCreate_NLGS(KergsSolver);
PETSC_INTERN PetscErrorCode KergsSolverCreate_NLKerGS(KergsSolver);
PETSC_INTERN PetscErrorCode KergsSolverCreate_NLGSJac(KergsSolver);
PETSC_INTERN PetscErrorCode KergsSolverCreate_Newton(KergsSolver);
PETSC_INTERN PetscErrorCode KergsSolverCreate_Tresca(KergsSolver);
PETSC_INTERN PetscErrorCode KergsSolverCreate_SnesVI(KergsSolver);

#endif
