/* kergs results: one HDF5 file per run, written through PetscViewerHDF5 under a temporary name and
   renamed when complete (atomic). Layout in docs/results.md:
     /stats/<name>                 one 1-D dataset per statistic, one entry per step
     /snapshots/<k>/...            grain ids, positions, velocities, radii; contact list
   Statistics are recorded by name each step (KergsResultsRecord), so components add their own. */
#ifndef KERGS_RESULTS_H
#define KERGS_RESULTS_H

#include <kergs/operators.h>

#define KERGS_RESULTS_MAXSTATS 64

typedef struct _p_KergsResults *KergsResults;
struct _p_KergsResults {
  MPI_Comm    comm;
  char        path[PETSC_MAX_PATH_LEN], tmppath[PETSC_MAX_PATH_LEN];
  PetscViewer viewer;
  PetscInt    snapshot_every; /* -output_every: steps between snapshots (0: first and last only) */
  PetscInt    nsnapshots;
  PetscInt    nstats, nrows, nalloc;
  char        statname[KERGS_RESULTS_MAXSTATS][64];
  PetscReal  *statvalues[KERGS_RESULTS_MAXSTATS];
  PetscBool   enabled;
};

PETSC_EXTERN PetscErrorCode KergsResultsCreate(MPI_Comm, KergsResults *);
PETSC_EXTERN PetscErrorCode KergsResultsSetFromOptions(KergsResults); /* -output, -output_every */
PETSC_EXTERN PetscErrorCode KergsResultsOpen(KergsResults);
/* Record one statistic of the current step (same call on every rank, values already reduced). */
PETSC_EXTERN PetscErrorCode KergsResultsRecord(KergsResults, const char name[], PetscReal value);
PETSC_EXTERN PetscErrorCode KergsResultsEndStep(KergsResults);
PETSC_EXTERN PetscErrorCode KergsResultsSnapshot(KergsResults, KergsScene, KergsContacts);
/* Write /stats, close and rename the temporary file to its final name. */
PETSC_EXTERN PetscErrorCode KergsResultsClose(KergsResults);
PETSC_EXTERN PetscErrorCode KergsResultsDestroy(KergsResults *);

#endif
