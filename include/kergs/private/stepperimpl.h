/* kergs stepper, private: the time loop's fields, for src/step/ only; other components go through kergs/stepper.h. */
#ifndef KERGS_STEPPERIMPL_H
#define KERGS_STEPPERIMPL_H

#include <kergs/stepper.h>

#define KERGS_STEPPER_MAXINPUTS 8

/* Input files named outside the options database (-options_file), for the checks of a run's paths: no output may
   replace one. */
typedef struct {
  PetscInt n;
  char     option[KERGS_STEPPER_MAXINPUTS][32], path[KERGS_STEPPER_MAXINPUTS][PETSC_MAX_PATH_LEN];
} KergsInputFiles;
PETSC_INTERN PetscErrorCode KergsInputFilesAdd(MPI_Comm, KergsInputFiles *, const char option[], const char path[]);

struct _p_KergsStepper {
  MPI_Comm       comm;
  KergsScene     scene;
  KergsContacts  contacts;
  KergsOperators ops;
  KergsSolver    solver;
  KergsResults   results;
  KergsPartition partition;                      /* ownership of the grains by the ranks (-partition_*) */
  PetscReal      rest_speed;                     /* -stop_at_rest: stop once every disk is slower than this (0: never) */
  PetscReal      rest_energy;                    /* -stop_at_rest_energy: or once the kinetic energy per grain is below this */
  PetscReal      rest_inertial;                  /* -stop_at_rest_inertial: or once the box's inertial number is below this */
  PetscInt       rest_window;                    /* -stop_at_rest_window: steps over which the box's strain rate is measured */
  PetscReal     *box_track;                      /* per step of that window: time, stress, each wall's normal position */
  PetscInt       box_tracked;                    /* steps tracked so far in this run (the ring's next slot modulo the window + 1) */
  PetscReal      box_inertial;                   /* the box's inertial number over the window (-1: the window is not full yet) */
  PetscReal      grain_d, grain_rho;             /* the grains' mean diameter and density (0: not measured yet) */
  PetscBool      inertial_armed;                 /* the box's inertial number has been at least -stop_at_rest_inertial */
  PetscReal      rest_stress;                    /* -stop_at_rest_stress: the inertial rule also waits for equilibrium */
  PetscReal      box_stress_gap;                 /* largest |n.(Love-Weber - boundary).n| / p, the window's mean */
  PetscBool      inertia_found;                  /* the walls make a box, and inertia_stress holds the latest step's */
  PetscReal      inertia_stress[3];              /* that step's Love-Weber minus boundary sxx, syy, sxy: the grains' inertia */
  char           sample_out[PETSC_MAX_PATH_LEN]; /* -sample_output */
  PetscBool      sample_forces;                  /* -sample_forces: the first step starts from the sample's contact forces */
  PetscInt       sample_nforces;                 /* how many forces it restored (all ranks) */
  PetscInt       fclib_step;                     /* -fclib_step: export this step's problem (-1: none) */
  char           fclib_path[PETSC_MAX_PATH_LEN];
  PetscBool      quiet;         /* -quiet: no per-step summary line */
  PetscBool      keep_H;        /* -keep_H: H_f, H_g live through the solve next to W (otherwise freed before W is built) */
  PetscReal      overlap_tol;   /* -initial_overlap_tol: initial interpenetration allowed, relative to the smaller radius */
  PetscInt       nonconverged;  /* steps that did not converge (KergsSolveStats.converged) */
  PetscReal      max_violation; /* largest interpenetration seen over the run */
  PetscReal      io_seconds;    /* snapshot time of the current step */
  PetscLogDouble step_start;    /* wall clock at the start of the current step */
  PetscLogDouble sent_start;    /* bytes this rank had sent (PETSc's message log) at the start of the current step */
  PetscReal      baseline_rss;  /* resident memory (bytes, summed over ranks) before the scene was built */
  /* batch use (docs/running.md) */
  char            restart_path[PETSC_MAX_PATH_LEN];    /* -restart: the checkpoint this run continues */
  char            checkpoint_path[PETSC_MAX_PATH_LEN]; /* -checkpoint_path */
  PetscInt        checkpoint_every;                    /* -checkpoint_every: steps between checkpoints (0: not by steps) */
  PetscReal       checkpoint_seconds;                  /* -checkpoint_seconds: wall time between checkpoints (0: not by time) */
  PetscBool       checkpointing;                       /* a checkpoint option was given: checkpoints as they say and at the end */
  PetscInt        checkpoint_step;                     /* step of the latest checkpoint this run wrote (-1: none) */
  PetscLogDouble  last_checkpoint;                     /* wall clock of the latest checkpoint, or of the start (rank 0 decides) */
  PetscInt        progress_every;                      /* -progress_every: a progress line every N steps (0: not by steps) */
  PetscReal       progress_seconds;                    /* -progress_seconds: ... and every T seconds (0: not by time) */
  PetscLogDouble  last_progress, loop_start;           /* wall clock of the latest progress line and of the start of the loop */
  PetscInt        progress_step, loop_start_step;      /* steps at those times */
  PetscBool       error_on_nonconvergence;             /* -error_on_nonconvergence: exit status 3 if a step did not converge */
  PetscBool       moved;                               /* -stop_at_rest: the packing has moved faster than rest_speed */
  KergsExitStatus status;                              /* how the run ended (KergsStepperGetExitStatus) */
  int             signal;                              /* the signal that stopped it (0: none) */
  KergsInputFiles inputs;                              /* input files named outside the options database (-options_file) */
  /* the latest step's figures, for the progress lines */
  PetscInt  last_contacts, last_sweeps;
  PetscReal last_residual, last_max_violation;
  PetscReal last_max_relative; /* the latest step's largest interpenetration over the smaller radius of its pair */
  /* the watch (src/step/watch.c, docs/running.md): blow-ups and solver failures */
  PetscReal       blowup_overlap;         /* -blowup_overlap: largest interpenetration / smaller radius (0: not checked) */
  PetscReal       blowup_energy;          /* -blowup_energy: largest kinetic energy over what the work explains (0: not checked) */
  PetscReal       divergence_tol;         /* -solver_divergence_tol: a natural residual above it is a diverged step (0: never) */
  PetscInt        divergence_steps;       /* -solver_divergence_steps: diverged steps in a row that stop the run */
  PetscInt        diverged_steps;         /* diverged steps in a row so far */
  PetscReal       ek_start, ek_end;       /* kinetic energy (disks and free walls) at the start and the end of the latest step */
  PetscReal       work;                   /* work of gravity and walls during the latest step */
  PetscReal       driven_work;            /* the driven walls' part of it */
  PetscBool       on_infeasible_continue; /* -on_infeasible continue: apply an infeasible step's answer and go on */
  PetscReal       vmax_end;               /* the fastest disk's speed at the end of the latest step */
  PetscBool       warned_alert;           /* the warning that grains outrun the alert distance was printed */
  PetscReal       energy_floor;           /* the scene's energy scale times 1e-6: kinetic energies below it are rounding */
  char            failure[512];           /* what went wrong in the latest step (empty: nothing) */
  KergsExitStatus failure_status;         /* and the exit status it gives */
  const char     *failure_kind;           /* in a few words, for the results file's end attribute */
};

/* The statistics of the step just taken, from what each component measured, handed to the results file, and the
   step's summary line (src/step/statistics.c). */
PETSC_INTERN PetscErrorCode KergsStepperRecordStep(KergsStepper, const KergsSolveStats *, PetscLogDouble detect_seconds,
                                                   PetscLogDouble assemble_seconds);
/* The macroscopic response of the step (src/step/macro.c, docs/results.md): stresses, strains, solid fraction,
   coordination, anisotropies and sliding contacts, into the current row, and the Love-Weber minus the boundary's stress
   into st->inertia_stress (what -stop_at_rest_stress reads). Collective. Whether the walls make the box it is measured
   in. */
PETSC_INTERN PetscErrorCode KergsStepperRecordMacro(KergsStepper);
PETSC_INTERN PetscErrorCode KergsStepperHasBox(KergsStepper, PetscBool *found);
/* The solve's figures (common ones, then the type's own figures and texts) into the current row. */
PETSC_INTERN PetscErrorCode KergsStepperRecordSolve(KergsResults, const KergsSolveStats *);
/* Batch use (src/step/batch.c, docs/running.md). */
/* What the time loop learns between two steps, the same on every rank (one reduction): a signal caught on some rank
   (0: none), a non-finite state (and the smallest grain id at fault, -1: a wall), a checkpoint due by rank 0's clock. */
typedef struct {
  int       signal;
  PetscBool blowup;
  PetscInt  blowup_grain;
  PetscBool checkpoint_time;
} KergsPoll;
PETSC_INTERN PetscErrorCode KergsStepperBatchOptions(KergsStepper);
PETSC_INTERN PetscErrorCode KergsStepperDefaultCheckpointPath(KergsStepper);
PETSC_INTERN PetscErrorCode KergsStepperCheckPaths(KergsStepper);
/* Install (on) or remove the handlers of SIGTERM, SIGINT and SIGUSR1 */
PETSC_INTERN PetscErrorCode KergsStepperCatchSignals(PetscBool on);
PETSC_INTERN const char    *KergsSignalName(int);
PETSC_INTERN PetscErrorCode KergsStepperPoll(KergsStepper, KergsPoll *);
/* Flush the results file and write the checkpoint of the current step (once per step) */
PETSC_INTERN PetscErrorCode KergsStepperCheckpoint(KergsStepper);
/* The state of -restart's checkpoint, after every object's SetFromOptions */
PETSC_INTERN PetscErrorCode KergsStepperRestore(KergsStepper);
/* A progress line when -progress_every or -progress_seconds says so (force: now) */
PETSC_INTERN PetscErrorCode KergsStepperProgress(KergsStepper, PetscBool force);

/* The watch (src/step/watch.c): its options; the first grain outside the container (-1: none) and the wall it is behind;
   the error of a grain outside before the first step; the kinetic energy of disks and free walls; the work of gravity
   and walls in the step just taken (V+ in place, V- given); the energy scale; the verdict after a step (st->failure). */
PETSC_INTERN PetscErrorCode KergsStepperWatchOptions(KergsStepper);
PETSC_INTERN PetscErrorCode KergsStepperFindOutside(KergsStepper, PetscInt *grain, PetscInt *wall);
PETSC_INTERN PetscErrorCode KergsStepperCheckContainer(KergsStepper);
PETSC_INTERN PetscErrorCode KergsStepperWarnInertialNumber(KergsStepper);
/* -stop_at_rest_inertial (src/step/inertial.c): the refusals of a scene whose box it cannot judge (before the run),
   the walls where the run starts, and, after each step, the box's inertial number over the window into st->box_inertial
   and the current row. Collective. */
PETSC_INTERN PetscErrorCode KergsStepperCheckRestInertial(KergsStepper);
PETSC_INTERN PetscErrorCode KergsStepperStartBox(KergsStepper);
PETSC_INTERN PetscErrorCode KergsStepperTrackBox(KergsStepper);
PETSC_INTERN PetscErrorCode KergsStepperEnergy(KergsStepper, PetscReal *ek, PetscReal *vmax);
/* Whether this rank's owned disks and the walls are finite: the first bad grain id (PETSC_MAX_INT: none; -1: a wall). */
PETSC_INTERN PetscInt       KergsStepperFirstNonFiniteGrain(KergsScene);
PETSC_INTERN PetscErrorCode KergsStepperExternalWork(KergsStepper, const PetscReal vold[], const PetscReal wvold[], PetscReal *work,
                                                     PetscReal *driven_work);
/* The message of a step the solver proved infeasible (KergsSolverGetInfeasibleNetwork): the grains and walls of the
   network, into st->failure with status 5. Collective. */
PETSC_INTERN PetscErrorCode KergsStepperReportInfeasible(KergsStepper, PetscInt step);
PETSC_INTERN PetscErrorCode KergsStepperEnergyFloor(KergsStepper);
PETSC_INTERN PetscErrorCode KergsStepperWatch(KergsStepper, const KergsSolveStats *);

/* Peak resident memory of the run so far, in bytes, summed over ranks */
PETSC_INTERN PetscErrorCode KergsStepperPeakMemory(MPI_Comm, PetscReal *bytes);

#endif
