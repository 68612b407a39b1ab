/* kergs checkpoint: the whole state of a run in one HDF5 file (src/io/checkpoint.c; layout in docs/results.md,
   "Checkpoint file"; use in docs/running.md), written atomically (<path>.tmp, renamed when complete: a crash while
   writing never damages the previous checkpoint).

   It holds every per-disk field (ids, positions, orientations, velocities, radii, materials) in global-index order
   with each rank's range, the walls (endpoints, velocities, displacements), the clock, the contact set with its
   impulses (warm start) in global order with each rank's count, the ghost layer (which disks, and the positions it
   was built from), the partition's state, the results file's state and the time loop's, and the options database as
   text. Restarted on the same number of ranks, the run continues bit for bit: same disk numbering and order per rank,
   same ghost layer, same contacts in the same order, same partition counters. On another number of ranks the disks
   are split evenly, partitioned anew, and the contacts' impulses warm-start a detection at the restored positions:
   the run continues to the solver's tolerance. */
#ifndef KERGS_CHECKPOINT_H
#define KERGS_CHECKPOINT_H

#include <kergs/partition.h>
#include <kergs/results.h>

/* What the time loop carries from step to step (kergs/stepper.h). */
typedef struct {
  PetscInt  nonconverged;  /* steps that did not converge so far */
  PetscReal max_violation; /* largest interpenetration seen so far */
  PetscBool moved;         /* -stop_at_rest: the packing has moved faster than the threshold */
  PetscBool armed;         /* -stop_at_rest_inertial: the box's inertial number has been above the threshold */
} KergsRunState;

/* Collective: write the state of the run to path (via path.tmp). The results file must be flushed first
   (KergsResultsFlush) so that it holds every row the checkpoint counts. */
PETSC_EXTERN PetscErrorCode KergsCheckpointWrite(const char path[], KergsScene, KergsContacts, KergsPartition, KergsResults,
                                                 const KergsRunState *);
/* Collective, after the objects' SetFromOptions (the scene with KergsSceneSetRestoring): restore the state of path into
   them (the results writer is told to continue the checkpointed run's file: KergsResultsSetContinue) and return the
   time loop's. Every field is checked against the options of this run (walls by name, materials), errors name the
   file. */
PETSC_EXTERN PetscErrorCode KergsCheckpointRead(const char path[], KergsScene, KergsContacts, KergsPartition, KergsResults,
                                                KergsRunState *);
/* Collective, before any object reads its options: the options of the checkpointed run (the root attribute `options`)
   enter the options database, except those already set (the command line overrides them) and -restart. */
PETSC_EXTERN PetscErrorCode KergsCheckpointLoadOptions(MPI_Comm, const char path[]);

#endif
