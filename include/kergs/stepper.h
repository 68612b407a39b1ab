/* kergs stepper: the time loop of Algorithm 1 (Moreau-Jean, theta-method):
   detect -> assemble -> solve -> V_f^+ = V_f^- + M^-1 (H_f r + R^d), x^+ = x^- + dt (theta V^+ + (1-theta) V^-)
   -> statistics and snapshots. */
#ifndef KERGS_STEPPER_H
#define KERGS_STEPPER_H

#include <kergs/solver.h>
#include <kergs/results.h>
#include <kergs/partition.h>

typedef struct _p_KergsStepper *KergsStepper;

/* How a run ended: the exit status of the kergs executable (docs/running.md). An error (bad input, I/O, a full disk,
   an internal error) ends the run through PETSc's error handling with status 1. */
typedef enum {
  KERGS_EXIT_DONE   = 0,        /* every step of -steps, or at rest (-stop_at_rest) */
  KERGS_EXIT_ERROR  = 1,        /* an error: the message names its cause */
  KERGS_EXIT_BLOWUP = 2,        /* a blow-up (a non-finite state, a grain out of the container, an interpenetration beyond
                                   -blowup_overlap, kinetic energy beyond -blowup_energy): the run stopped after that step */
  KERGS_EXIT_NOT_CONVERGED = 3, /* done, but some step did not converge, with -error_on_nonconvergence */
  KERGS_EXIT_SIGNAL        = 4, /* stopped by SIGTERM, SIGINT or SIGUSR1 after finishing the step: checkpoint written, files closed */
  KERGS_EXIT_SOLVER_FAILED = 5  /* the contact solver diverged (-solver_divergence_tol): the run stopped after that step */
} KergsExitStatus;

PETSC_EXTERN PetscErrorCode KergsStepperCreate(MPI_Comm, KergsStepper *);
PETSC_EXTERN PetscErrorCode KergsStepperSetFromOptions(KergsStepper);
/* One line saying what runs, then -scene_view and -solver_view if given. Collective. */
PETSC_EXTERN PetscErrorCode KergsStepperViewFromOptions(KergsStepper);
PETSC_EXTERN PetscErrorCode KergsStepperStep(KergsStepper);
/* The whole run: the time loop with its snapshots, checkpoints (-checkpoint_*), progress lines (-progress_*) and signals
   (SIGTERM, SIGINT, SIGUSR1: the loop finishes the step, writes a checkpoint and closes the files); the results file is
   closed under its final name whatever the ending but an error. */
PETSC_EXTERN PetscErrorCode KergsStepperRun(KergsStepper);
/* After KergsStepperRun: how it ended (KERGS_EXIT_DONE before) */
PETSC_EXTERN PetscErrorCode KergsStepperGetExitStatus(KergsStepper, KergsExitStatus *);
/* An input file that the options database does not keep (-options_file), for the checks of the run's paths: no output
   may replace it. Before KergsStepperSetFromOptions. */
PETSC_EXTERN PetscErrorCode KergsStepperAddInput(KergsStepper, const char option[], const char path[]);
PETSC_EXTERN PetscErrorCode KergsStepperDestroy(KergsStepper *);
/* on: kergs's handler of SIGTERM, SIGINT and SIGUSR1 (a flag that the time loop polls between steps, and before the
   first: a signal during the set-up stops the run before step 1); installed again if something replaced it. off: the
   dispositions found before. Plain C, callable before PetscInitialize (main calls it first thing, and again after
   PetscInitialize: a signal in the first second of a batch job must not kill the run). 0 on success. */
PETSC_EXTERN int KergsStepperCatchStopSignals(PetscBool on);

/* Accessors: the objects a time step works on (owned by the stepper). */
PETSC_EXTERN PetscErrorCode KergsStepperGetScene(KergsStepper, KergsScene *);
PETSC_EXTERN PetscErrorCode KergsStepperGetContacts(KergsStepper, KergsContacts *);
PETSC_EXTERN PetscErrorCode KergsStepperGetOperators(KergsStepper, KergsOperators *);
PETSC_EXTERN PetscErrorCode KergsStepperGetSolver(KergsStepper, KergsSolver *);
PETSC_EXTERN PetscErrorCode KergsStepperGetResults(KergsStepper, KergsResults *);
PETSC_EXTERN PetscErrorCode KergsStepperGetPartition(KergsStepper, KergsPartition *);
/* Over the run so far: steps whose solve did not converge, and the largest interpenetration seen */
PETSC_EXTERN PetscErrorCode KergsStepperGetRunSummary(KergsStepper, PetscInt *nonconverged, PetscReal *max_violation);

/* -fclib_input FILE: one FCLib problem (kergs/fclib.h) solved by the solver of the options instead of a scene's time loop,
   its statistics recorded as one step's (-output) and printed as one summary line (src/step/fclib_run.c). SetFromOptions
   reads -fclib_input, the solver's and the results' options and the file, and checks the paths; the types that need the
   scene's H_f are refused. Solve: the exit status is KERGS_EXIT_NOT_CONVERGED with -error_on_nonconvergence when the solve
   did not converge, otherwise KERGS_EXIT_DONE. */
typedef struct _p_KergsFCLibRun *KergsFCLibRun;
PETSC_EXTERN PetscErrorCode      KergsFCLibRunCreate(MPI_Comm, KergsFCLibRun *);
/* as KergsStepperAddInput: an options file that no output may replace; before KergsFCLibRunSetFromOptions */
PETSC_EXTERN PetscErrorCode KergsFCLibRunAddInput(KergsFCLibRun, const char option[], const char path[]);
PETSC_EXTERN PetscErrorCode KergsFCLibRunSetFromOptions(KergsFCLibRun);
PETSC_EXTERN PetscErrorCode KergsFCLibRunGetSolver(KergsFCLibRun, KergsSolver *);
PETSC_EXTERN PetscErrorCode KergsFCLibRunSolve(KergsFCLibRun, KergsExitStatus *);
PETSC_EXTERN PetscErrorCode KergsFCLibRunDestroy(KergsFCLibRun *);
/* With -help: list the options of -fclib_input runs. Collective. */
PETSC_EXTERN PetscErrorCode KergsFCLibRunPrintHelp(MPI_Comm);

#endif
