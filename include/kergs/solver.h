/* kergs solver: solves the per-step problem W r - v = -v^d with the contact law (eq. 1, 2).
   Variants are types registered by name, chosen with -solver_type (like KSPType):
     nlgs     Algorithm 2 (plain NLGS on W)
     nlkergs  Algorithm 3 (NLKerGS-P) on an explicitly stored W~ = W + omega N N^T: small problems, verification
     nlgsjac  Algorithm 6 (NLGS-Jac): Gauss-Seidel on W, Jacobi on the dense part omega N N^T, never stored
     newton   semismooth Newton on the Alart-Curnier function, proximal outer iterations
     tresca   Tresca fixed point, each Tresca problem a bound-constrained QP solved by PETSc TAO
     snesvi   the law as a mixed complementarity problem, solved by PETSc's SNESVI (Fischer-Burmeister or active set)
   Options: -solver_max_it (paper: 150), -solver_tol, -solver_criterion quad|maxm|natural; the regularised types
   add -solver_omega, -solver_omega_factor, the kernel's (-kernel_*) and the predictor's (-predictor_*). */
#ifndef KERGS_SOLVER_H
#define KERGS_SOLVER_H

#include <kergs/operators.h>

typedef const char *KergsSolverType;
#define KERGS_SOLVER_NLGS "nlgs"
#define KERGS_SOLVER_NLKERGS "nlkergs"
#define KERGS_SOLVER_NLGSJAC "nlgsjac"
#define KERGS_SOLVER_NEWTON "newton"
#define KERGS_SOLVER_TRESCA "tresca"
#define KERGS_SOLVER_SNESVI "snesvi"

typedef enum { KERGS_CRITERION_QUAD, KERGS_CRITERION_MAXM, KERGS_CRITERION_NATURAL } KergsCriterion;
PETSC_EXTERN const char *const KergsCriteria[];

/* A named figure of a solve (KergsSolveStats): the time step hands them to the results file as statistics. */
#define KERGS_SOLVE_MAXEXTRA 32
typedef struct {
  char      name[32];
  PetscReal value;
} KergsNamedValue;
/* A named text of a solve, such as the type of a sub-object: recorded once per run. */
#define KERGS_SOLVE_MAXTEXT 4
typedef struct {
  char name[32];
  char value[64];
} KergsNamedText;

/* Why a solve stopped (KergsSolveStats.reason), in the manner of KSPConvergedReason: positive when the step's problem
   is solved (by which criterion), negative when it is not (why), 0 while the solve runs. -solver_converged_reason
   prints it after every solve; /stats records it as converged_reason, its names as that dataset's attribute. */
typedef enum {
  KERGS_SOLVER_DIVERGED_NANORINF = -6,     /* the impulses or their residual are not finite */
  KERGS_SOLVER_DIVERGED_KERNEL   = -5,     /* the kernel projector misses ker H_f (the regularised types): the time loop
                                              stops with status 5 */
  KERGS_SOLVER_DIVERGED_LINEAR_SOLVE = -4, /* a linear solve the type cannot do without failed */
  KERGS_SOLVER_DIVERGED_INFEASIBLE   = -3, /* the step's problem has no solution */
  KERGS_SOLVER_DIVERGED_RESIDUAL     = -2, /* the type's own criterion was met, but r does not solve the original problem:
                                              natural residual above -solver_residual_tol or velocity error above
                                              -solver_velocity_tol (docs/solver.md) */
  KERGS_SOLVER_DIVERGED_MAX_IT       = -1, /* -solver_max_it iterations without meeting the criterion */
  KERGS_SOLVER_CONVERGED_ITERATING   = 0,
  KERGS_SOLVER_CONVERGED_QUAD        = 1, /* -solver_criterion quad below -solver_tol, and the original problem solved */
  KERGS_SOLVER_CONVERGED_MAXM        = 2, /* maxm below -solver_tol, and the original problem solved */
  KERGS_SOLVER_CONVERGED_NATURAL     = 3, /* the natural residual below -solver_tol (and the original problem solved) */
  KERGS_SOLVER_CONVERGED_NO_CONTACTS = 4  /* nothing to solve: the step has no contact */
} KergsSolverConvergedReason;
/* The names, indexed by reason: KergsSolverConvergedReasons[KERGS_SOLVER_DIVERGED_MAX_IT] is "DIVERGED_MAX_IT". */
PETSC_EXTERN const char *const *KergsSolverConvergedReasons;
#define KERGS_SOLVER_REASON_MIN KERGS_SOLVER_DIVERGED_NANORINF
#define KERGS_SOLVER_REASON_MAX KERGS_SOLVER_CONVERGED_NO_CONTACTS

/* What a solve found and cost (KergsSolverSolve). */
typedef struct {
  PetscInt                   iterations;
  KergsSolverConvergedReason reason;
  PetscReal                  criterion;       /* value of the chosen criterion at exit */
  PetscReal                  residual;        /* natural-map residual of the original problem, recomputed from r at exit */
  PetscReal                  velocity_error;  /* the law's worst violation in velocity, relative to the problem's (kergs/sweep.h) */
  PetscReal                  seconds;         /* whole solve: set-up, sweeps, final residual */
  PetscReal                  sweep_seconds;   /* the sweeps alone */
  PetscReal                  compute_seconds; /* this rank's arithmetic in the sweeps (no waiting for messages or reductions) */
  PetscInt                   nextra;          /* the type's own figures of the step (kernel, predictor, omega, ...) */
  KergsNamedValue            extra[KERGS_SOLVE_MAXEXTRA];
  PetscInt                   ntext; /* the type's own texts (predictor type, ...) */
  KergsNamedText             text[KERGS_SOLVE_MAXTEXT];
} KergsSolveStats;
/* Add a named figure or text to the statistics of a solve (for the types). */
PETSC_EXTERN PetscErrorCode KergsSolveStatsAdd(KergsSolveStats *, const char name[], PetscReal value);
PETSC_EXTERN PetscErrorCode KergsSolveStatsAddText(KergsSolveStats *, const char name[], const char value[]);
/* A one-line description of a reason, for messages ("-solver_max_it reached", ...) */
PETSC_EXTERN const char *KergsSolverConvergedReasonDescription(KergsSolverConvergedReason);

typedef struct _p_KergsSolver *KergsSolver;

PETSC_EXTERN PetscErrorCode KergsSolverRegister(const char[], PetscErrorCode (*)(KergsSolver));
PETSC_EXTERN PetscErrorCode KergsSolverCreate(MPI_Comm, KergsSolver *);
PETSC_EXTERN PetscErrorCode KergsSolverSetType(KergsSolver, KergsSolverType);
PETSC_EXTERN PetscErrorCode KergsSolverSetFromOptions(KergsSolver);
PETSC_EXTERN PetscErrorCode KergsSolverSolve(KergsSolver, KergsScene, KergsContacts, KergsOperators, KergsSolveStats *);
PETSC_EXTERN PetscErrorCode KergsSolverView(KergsSolver, PetscViewer);
PETSC_EXTERN PetscErrorCode KergsSolverViewFromOptions(KergsSolver, const char name[]);
PETSC_EXTERN PetscErrorCode KergsSolverSetOptionsPrefix(KergsSolver, const char[]);
PETSC_EXTERN PetscErrorCode KergsSolverGetOptionsPrefix(KergsSolver, const char *[]);
PETSC_EXTERN PetscErrorCode KergsSolverDestroy(KergsSolver *);
/* With -help: print the options of every registered type, not only of the chosen one. Collective. */
PETSC_EXTERN PetscErrorCode KergsSolverPrintHelpAllTypes(MPI_Comm);

/* Monitors (as KSPMonitorSet): called once per iteration of a solve (a sweep, or a Newton step) with the step number
   (KergsSolverSetStepNumber), the iteration (1, 2, ...), the value of the type's own criterion, the natural residual of
   the original problem where the type computes it (NaN otherwise; the last iteration's is the residual recorded at exit)
   and the seconds since the solve started. -solver_monitor [ascii:FILE] sets KergsSolverMonitorDefault. */
typedef PetscErrorCode (*KergsSolverMonitorFn)(KergsSolver, PetscInt step, PetscInt it, PetscReal criterion, PetscReal residual,
                                               PetscReal seconds, void *ctx);
PETSC_EXTERN PetscErrorCode KergsSolverMonitorSet(KergsSolver, KergsSolverMonitorFn, void *ctx, PetscErrorCode (*destroy)(void **));
PETSC_EXTERN PetscErrorCode KergsSolverMonitorCancel(KergsSolver);
/* One line per iteration on a PetscViewerAndFormat's ASCII viewer (ctx) */
PETSC_EXTERN PetscErrorCode KergsSolverMonitorDefault(KergsSolver, PetscInt, PetscInt, PetscReal, PetscReal, PetscReal, void *);
/* The step number the next solves belong to (the step lines' numbering), for the monitors */
PETSC_EXTERN PetscErrorCode KergsSolverSetStepNumber(KergsSolver, PetscInt);

/* Accessors. */
PETSC_EXTERN PetscErrorCode KergsSolverGetType(KergsSolver, KergsSolverType *);
/* After a solve that ended DIVERGED_INFEASIBLE: per local contact, its weight (0 to 1) in the compressive
   self-equilibrated network that proves the step has no solution; NULL otherwise. Valid until the next solve. */
PETSC_EXTERN PetscErrorCode KergsSolverGetInfeasibleNetwork(KergsSolver, const PetscReal **weights);
/* Per local contact, whether it was active in the last solve (valid until the next solve) */
PETSC_EXTERN PetscErrorCode KergsSolverGetActive(KergsSolver, const PetscBool **active);
/* Whether the type reads H_f and H_g during its solve (the kernel projector of the regularised types and of newton's
   -solver_prox kernel, the predictors): the time step then keeps H alive from assembly to the velocity update. */
PETSC_EXTERN PetscErrorCode KergsSolverNeedsH(KergsSolver, PetscBool *);
/* Whether the type works on W over all pairs of potential contacts (the kernel-regularised types): the time step then
   assembles the whole W; otherwise W couples the active contacts only. */
PETSC_EXTERN PetscErrorCode KergsSolverNeedsFullW(KergsSolver, PetscBool *);
/* Whether the type reads W with both triangles (KergsOperatorsGetFullW: newton, tresca, snesvi, nlkergs) */
PETSC_EXTERN PetscErrorCode KergsSolverNeedsBothTriangles(KergsSolver, PetscBool *);
/* -solver_max_it and -solver_tol */
PETSC_EXTERN PetscErrorCode KergsSolverGetTolerances(KergsSolver, PetscReal *tol, PetscInt *max_it);
PETSC_EXTERN PetscErrorCode KergsSolverGetIterationName(KergsSolver, const char **);
#endif
