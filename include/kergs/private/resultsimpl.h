/* kergs results, private: the results writer's fields, for src/io/results.c only; other components go through
   kergs/results.h. */
#ifndef KERGS_RESULTSIMPL_H
#define KERGS_RESULTSIMPL_H

#include <kergs/results.h>

#define KERGS_RESULTS_MAXTEXTS 16

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
  char        scenename[PETSC_MAX_PATH_LEN]; /* names the default output path results/<scenename>.h5 */
  PetscInt    last_snapshot_step;            /* step of the latest snapshot (-1: none yet) */
  PetscInt    ntexts;                        /* texts of the run (KergsResultsRecordText), string attributes of /stats */
  char        textname[KERGS_RESULTS_MAXTEXTS][64], textvalue[KERGS_RESULTS_MAXTEXTS][256];
};

#endif
