/* kergs stepper, private: the time loop's fields, for src/step/ only; other components go through kergs/stepper.h. */
#ifndef KERGS_STEPPERIMPL_H
#define KERGS_STEPPERIMPL_H

#include <kergs/stepper.h>

struct _p_KergsStepper {
  MPI_Comm       comm;
  KergsScene     scene;
  KergsContacts  contacts;
  KergsOperators ops;
  KergsSolver    solver;
  KergsResults   results;
  KergsPartition partition;                      /* ownership of the grains by the ranks (-partition_*) */
  PetscReal      rest_speed;                     /* -stop_at_rest: stop once every disk is slower than this (0: never) */
  char           sample_out[PETSC_MAX_PATH_LEN]; /* -sample_output */
  PetscInt       fclib_step;                     /* -fclib_step: export this step's problem (-1: none) */
  char           fclib_path[PETSC_MAX_PATH_LEN];
  PetscBool      quiet;         /* -quiet: no per-step summary line */
  PetscBool      keep_H;        /* -keep_H: H_f, H_g live through the solve next to W (otherwise freed before W is built) */
  PetscReal      overlap_tol;   /* -initial_overlap_tol: initial interpenetration allowed, relative to the smaller radius */
  PetscInt       nonconverged;  /* steps whose solve hit max_it */
  PetscReal      max_violation; /* largest interpenetration seen over the run */
  PetscReal      io_seconds;    /* snapshot time of the current step */
  PetscLogDouble step_start;    /* wall clock at the start of the current step */
  PetscLogDouble sent_start;    /* bytes this rank had sent (PETSc's message log) at the start of the current step */
  PetscReal      baseline_rss;  /* resident memory (bytes, summed over ranks) before the scene was built */
};

/* The statistics of the step just taken, from what each component measured, handed to the results file, and the
   step's summary line (src/step/statistics.c). */
PETSC_INTERN PetscErrorCode KergsStepperRecordStep(KergsStepper, const KergsSolveStats *, PetscLogDouble detect_seconds,
                                                   PetscLogDouble assemble_seconds);
/* Peak resident memory of the run so far, in bytes, summed over ranks */
PETSC_INTERN PetscErrorCode KergsStepperPeakMemory(MPI_Comm, PetscReal *bytes);

#endif
