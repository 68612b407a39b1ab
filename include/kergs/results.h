/* kergs results: one HDF5 file per run, written through PetscViewerHDF5 under a temporary name and
   renamed when complete (atomic). Layout in docs/results.md:
     /stats/<name>                 one 1-D dataset per statistic, one entry per step
     /snapshots/<k>/...            grain ids, positions, velocities, radii; contact list
   Statistics are recorded by name each step (KergsResultsRecord), so components add their own.
   A statistic first recorded after some rows were completed gets NaN in those earlier rows, and a
   statistic not recorded in a step gets NaN in that row.

   Use: Create, (SetSceneName), SetFromOptions, Open; per step Record ... EndStep and, when
   KergsResultsSnapshotDue says so, Snapshot; Close at the end; Destroy. With -output_none every call
   is a no-op. */
#ifndef KERGS_RESULTS_H
#define KERGS_RESULTS_H

#include <kergs/detect.h>

#define KERGS_RESULTS_MAXSTATS 64

typedef struct _p_KergsResults *KergsResults;

PETSC_EXTERN PetscErrorCode KergsResultsCreate(MPI_Comm, KergsResults *);
/* Name used for the default path results/<name>.h5 when -output is not given (call before Open;
   without it the default is results/kergs.h5). */
PETSC_EXTERN PetscErrorCode KergsResultsSetSceneName(KergsResults, const char name[]);
PETSC_EXTERN PetscErrorCode KergsResultsSetFromOptions(KergsResults); /* -output, -output_every, -output_none */
PETSC_EXTERN PetscErrorCode KergsResultsOpen(KergsResults);
/* Record one statistic of the current step (same call on every rank, values already reduced). */
PETSC_EXTERN PetscErrorCode KergsResultsRecord(KergsResults, const char name[], PetscReal value);
PETSC_EXTERN PetscErrorCode KergsResultsEndStep(KergsResults);
/* Record a text of the run (a type name, ...) as a string attribute of /stats; the last value given is kept. */
PETSC_EXTERN PetscErrorCode KergsResultsRecordText(KergsResults, const char name[], const char value[]);
/* The statistic `name` of step row `row` (-1: the last completed row), as recorded so far; *found tells whether it was
   recorded (NaN for a row where it was not). */
PETSC_EXTERN PetscErrorCode KergsResultsGetStatistic(KergsResults, const char name[], PetscInt row, PetscReal *value, PetscBool *found);
/* Rows completed so far */
PETSC_EXTERN PetscErrorCode KergsResultsGetNumRows(KergsResults, PetscInt *);
/* The results file's path, and whether results are written at all (-output_none) */
PETSC_EXTERN PetscErrorCode KergsResultsGetPath(KergsResults, const char **path, PetscBool *enabled);
/* Whether the snapshot policy asks for a snapshot at this step: the first snapshot of the run (none
   written yet), the last step (last = PETSC_TRUE), and with -output_every N > 0 every step that is a
   multiple of N. Always PETSC_FALSE with -output_none. */
PETSC_EXTERN PetscErrorCode KergsResultsSnapshotDue(KergsResults, PetscInt step, PetscBool last, PetscBool *due);
/* Write /snapshots/<k> for the scene's current step (collective). A second call for the same step is
   ignored, so a final unconditional call after the loop does not duplicate the last snapshot. */
PETSC_EXTERN PetscErrorCode KergsResultsSnapshot(KergsResults, KergsScene, KergsContacts);
/* Write /stats, close and rename the temporary file to its final name. */
PETSC_EXTERN PetscErrorCode KergsResultsClose(KergsResults);
PETSC_EXTERN PetscErrorCode KergsResultsDestroy(KergsResults *);

/* Helpers for atomic output files, shared by the io component (collective on comm; rank 0 does the file
   system work and every rank gets the same error):
   KergsFileMakeParentDir creates the directories leading to path (like mkdir -p of its dirname);
   KergsFileCommit waits for every rank (after the file was closed everywhere), then renames tmp to path. */
PETSC_EXTERN PetscErrorCode KergsFileMakeParentDir(MPI_Comm, const char path[]);
PETSC_EXTERN PetscErrorCode KergsFileCommit(MPI_Comm, const char tmp[], const char path[]);
/* Shared by the HDF5 writers (results, samples): one dataset from the nlocal blocks of bs values this rank holds,
   stacked in rank order; integers are stored as reals (exact up to 2^53). Collective. */
PETSC_EXTERN PetscErrorCode KergsViewBlocks(PetscViewer, MPI_Comm, const char name[], PetscInt nlocal, PetscInt bs,
                                            const PetscReal *values);
PETSC_EXTERN PetscErrorCode KergsViewIntegers(PetscViewer, MPI_Comm, const char name[], PetscInt nlocal, const PetscInt *values);

#endif
