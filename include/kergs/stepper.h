/* kergs stepper: the time loop of Algorithm 1 (Moreau-Jean, theta-method):
   detect -> assemble -> solve -> V_f^+ = V_f^- + M^-1 (H_f r + R^d), x^+ = x^- + dt (theta V^+ + (1-theta) V^-)
   -> statistics and snapshots. */
#ifndef KERGS_STEPPER_H
#define KERGS_STEPPER_H

#include <kergs/solver.h>
#include <kergs/results.h>
#include <kergs/partition.h>

typedef struct _p_KergsStepper *KergsStepper;
struct _p_KergsStepper {
  MPI_Comm       comm;
  KergsScene     scene;
  KergsContacts  contacts;
  KergsOperators ops;
  KergsSolver    solver;
  KergsResults   results;
  KergsPartition partition;      /* ownership of the grains by the ranks (-partition_*) */
  PetscReal      rest_speed;     /* -stop_at_rest: stop once every disk is slower than this (0: never) */
  char           sample_out[PETSC_MAX_PATH_LEN]; /* -sample_output */
  PetscInt       fclib_step;     /* -fclib_step: export this step's problem (-1: none) */
  char           fclib_path[PETSC_MAX_PATH_LEN];
  PetscBool      quiet;          /* -quiet: no per-step summary line */
  PetscBool      keep_H;         /* -keep_H: H_f, H_g live through the solve next to W (otherwise freed before W is built) */
  PetscReal      overlap_tol;    /* -initial_overlap_tol: initial interpenetration allowed, relative to the smaller radius */
  PetscInt       nonconverged;   /* steps whose solve hit max_it */
  PetscReal      max_violation;  /* largest interpenetration seen over the run */
  PetscReal      io_seconds;     /* snapshot time of the current step */
  PetscLogDouble step_start;     /* wall clock at the start of the current step */
  PetscLogDouble sent_start;     /* bytes this rank had sent (PETSc's message log) at the start of the current step */
  PetscReal      baseline_rss;   /* resident memory (bytes, summed over ranks) before the scene was built */
};

PETSC_EXTERN PetscErrorCode KergsStepperCreate(MPI_Comm, KergsStepper *);
PETSC_EXTERN PetscErrorCode KergsStepperSetFromOptions(KergsStepper);
PETSC_EXTERN PetscErrorCode KergsStepperStep(KergsStepper);
PETSC_EXTERN PetscErrorCode KergsStepperRun(KergsStepper);
PETSC_EXTERN PetscErrorCode KergsStepperDestroy(KergsStepper *);

#endif
