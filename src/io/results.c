/* kergs results: one HDF5 file per run (statistics per step and snapshots of the packing), written
   through PetscViewerHDF5 to "<path>.tmp" and renamed to <path> only once complete, so a run that dies
   leaves no file that looks finished. The layout is documented in docs/results.md. */
#include <kergs/private/resultsimpl.h>
#include <petscviewerhdf5.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

#define KERGS_RESULTS_INITIAL_ROWS 64
#define KERGS_WALL_COLUMNS (2 * KERGS_DIM) /* a and b endpoints */

/* ---------------------------------------------------------------------------------------------
   Atomic files: rank 0 touches the file system, every rank learns the outcome. */

/* Broadcast rank 0's message; a non-empty one becomes the same error on every rank. */
static PetscErrorCode RaiseFromRoot(MPI_Comm comm, PetscErrorCode code, char msg[], int len)
{
  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Bcast(msg, len, MPI_CHAR, 0, comm));
  PetscCheck(msg[0] == 0, comm, code, "%s", msg);
  PetscFunctionReturn(0);
}

/* mkdir -p of the directory part of path (rank 0 only); the message is empty on success. */
static void MakeDirectories(const char path[], char msg[], size_t len)
{
  char dir[PETSC_MAX_PATH_LEN];

  msg[0] = 0;
  if (strlen(path) >= sizeof(dir)) {
    snprintf(msg, len, "Output path %s is too long", path);
    return;
  }
  strcpy(dir, path);
  {
    char *slash = strrchr(dir, '/');
    if (!slash || slash == dir) return; /* in the current directory, or directly under / */
    *slash = 0;
  }
  for (char *p = dir + 1;; p++) {
    const char saved = *p;
    if (saved != '/' && saved != 0) continue;
    *p = 0;
    if (mkdir(dir, 0777) && errno != EEXIST) {
      snprintf(msg, len, "Cannot create directory %s for output file %s: %s", dir, path, strerror(errno));
      return;
    }
    *p = saved;
    if (!saved) break;
  }
  {
    struct stat st;
    if (stat(dir, &st) || !S_ISDIR(st.st_mode))
      snprintf(msg, len, "Cannot use %s as the directory of output file %s: not a directory", dir, path);
  }
}

PetscErrorCode KergsFileMakeParentDir(MPI_Comm comm, const char path[])
{
  char        msg[PETSC_MAX_PATH_LEN + 256] = "";
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) MakeDirectories(path, msg, sizeof(msg));
  PetscCall(RaiseFromRoot(comm, PETSC_ERR_FILE_OPEN, msg, (int)sizeof(msg)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsFileCommit(MPI_Comm comm, const char tmp[], const char path[])
{
  char        msg[2 * PETSC_MAX_PATH_LEN + 128] = "";
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Barrier(comm)); /* every rank has closed its handle on tmp */
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0 && rename(tmp, path)) snprintf(msg, sizeof(msg), "Cannot rename %s to %s: %s", tmp, path, strerror(errno));
  PetscCall(RaiseFromRoot(comm, PETSC_ERR_FILE_WRITE, msg, (int)sizeof(msg)));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------
   Lifetime and options */

PetscErrorCode KergsResultsCreate(MPI_Comm comm, KergsResults *res)
{
  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscNew(res));
  (*res)->comm               = comm;
  (*res)->enabled            = PETSC_TRUE;
  (*res)->snapshot_every     = 0;
  (*res)->last_snapshot_step = -1;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsSetSceneName(KergsResults res, const char name[])
{
  PetscFunctionBeginUser;
  PetscCall(PetscStrncpy(res->scenename, name ? name : "", sizeof(res->scenename)));
  PetscFunctionReturn(0);
}

/* results/<scene name>.h5, with the scene name reduced to its last path component. */
static PetscErrorCode ResultsDefaultPath(KergsResults res, char path[], size_t len)
{
  const char *name = res->scenename, *slash = strrchr(res->scenename, '/');

  PetscFunctionBeginUser;
  if (slash) name = slash + 1;
  if (!name[0]) name = "kergs";
  PetscCall(PetscSNPrintf(path, len, "results/%s.h5", name));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsSetFromOptions(KergsResults res)
{
  char      defpath[PETSC_MAX_PATH_LEN], path[PETSC_MAX_PATH_LEN];
  PetscBool set, none = (PetscBool)!res->enabled;

  PetscFunctionBeginUser;
  PetscCall(ResultsDefaultPath(res, defpath, sizeof(defpath)));
  PetscCall(PetscStrncpy(path, res->path[0] ? res->path : defpath, sizeof(path)));
  PetscOptionsBegin(res->comm, NULL, "Output options", "KergsResults");
  PetscCall(PetscOptionsString("-output", "Results file (HDF5: /stats per step, /snapshots); written to <path>.tmp, renamed when complete",
                               "KergsResultsSetFromOptions", path, path, sizeof(path), &set));
  if (set) PetscCall(PetscStrncpy(res->path, path, sizeof(res->path)));
  PetscCall(PetscOptionsInt("-output_every", "Snapshot every N steps (0: only the first and the last step)", "KergsResultsSnapshotDue",
                            res->snapshot_every, &res->snapshot_every, NULL));
  PetscCall(PetscOptionsBool("-output_none", "Write no results file", "KergsResultsSetFromOptions", none, &none, NULL));
  PetscOptionsEnd();
  PetscCall(KergsOptionsCheckInt(res->comm, NULL, "-output_every"));
  PetscCheck(res->snapshot_every >= 0, res->comm, PETSC_ERR_ARG_OUTOFRANGE, "Option -output_every must be >= 0, got %" PetscInt_FMT,
             res->snapshot_every);
  PetscCheck(!set || path[0], res->comm, PETSC_ERR_ARG_WRONG, "Option -output needs a file name (use -output_none for no results file)");
  res->enabled = (PetscBool)!none;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsOpen(KergsResults res)
{
  PetscFunctionBeginUser;
  if (!res->enabled) PetscFunctionReturn(0);
  PetscCheck(!res->viewer, res->comm, PETSC_ERR_ORDER, "Results file %s is already open", res->tmppath);
  if (!res->path[0]) PetscCall(ResultsDefaultPath(res, res->path, sizeof(res->path)));
  PetscCall(PetscSNPrintf(res->tmppath, sizeof(res->tmppath), "%s.tmp", res->path));
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(KergsFileMakeParentDir(res->comm, res->path));
  PetscCall(PetscViewerHDF5Open(res->comm, res->tmppath, FILE_MODE_WRITE, &res->viewer));
  PetscCall(PetscViewerHDF5SetBaseDimension2(res->viewer, PETSC_FALSE)); /* the documented layout: 1-D scalars, float64 */
  PetscCall(PetscViewerHDF5SetSPOutput(res->viewer, PETSC_FALSE));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "kergs_format", PETSC_STRING, "kergs results 1"));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "dim", PETSC_INT, &(PetscInt){KERGS_DIM}));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  res->nsnapshots         = 0;
  res->last_snapshot_step = -1;
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------
   Statistics: a table kept on every rank, one column per name, one row per step. Unset cells are NaN. */

static void FillNaN(PetscReal *a, PetscInt from, PetscInt to)
{
  for (PetscInt i = from; i < to; i++) a[i] = (PetscReal)NAN;
}

/* Make room for row index `row` in every column (capacity doubles). */
static PetscErrorCode ResultsReserveRow(KergsResults res, PetscInt row)
{
  PetscInt nalloc = res->nalloc ? res->nalloc : KERGS_RESULTS_INITIAL_ROWS;

  PetscFunctionBeginUser;
  if (row < res->nalloc) PetscFunctionReturn(0);
  while (nalloc <= row) nalloc *= 2;
  for (PetscInt j = 0; j < res->nstats; j++) {
    PetscReal *grown;
    PetscCall(PetscMalloc1(nalloc, &grown));
    PetscCall(PetscArraycpy(grown, res->statvalues[j], res->nalloc));
    FillNaN(grown, res->nalloc, nalloc);
    PetscCall(PetscFree(res->statvalues[j]));
    res->statvalues[j] = grown;
  }
  res->nalloc = nalloc;
  PetscFunctionReturn(0);
}

/* Column index of a statistic, created (NaN in every earlier row) on first use. */
static PetscErrorCode ResultsColumn(KergsResults res, const char name[], PetscInt *col)
{
  PetscBool same;

  PetscFunctionBeginUser;
  for (PetscInt j = 0; j < res->nstats; j++) {
    PetscCall(PetscStrcmp(res->statname[j], name, &same));
    if (same) {
      *col = j;
      PetscFunctionReturn(0);
    }
  }
  PetscCheck(res->nstats < KERGS_RESULTS_MAXSTATS, res->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Too many statistics (at most %d) when adding \"%s\" to %s", KERGS_RESULTS_MAXSTATS, name, res->path);
  PetscCheck(name[0] && strlen(name) < sizeof(res->statname[0]) && !strchr(name, '/'), res->comm, PETSC_ERR_ARG_WRONG,
             "Statistic name \"%s\" must be non-empty, shorter than %d characters and without '/'", name, (int)sizeof(res->statname[0]));
  PetscCall(ResultsReserveRow(res, res->nrows));
  *col = res->nstats++;
  PetscCall(PetscStrncpy(res->statname[*col], name, sizeof(res->statname[0])));
  PetscCall(PetscMalloc1(res->nalloc, &res->statvalues[*col]));
  FillNaN(res->statvalues[*col], 0, res->nalloc);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsRecord(KergsResults res, const char name[], PetscReal value)
{
  PetscInt col = -1;

  PetscFunctionBeginUser;
  /* kept in memory even with -output_none: the run's callers read them */
  PetscCall(ResultsColumn(res, name, &col));
  res->statvalues[col][res->nrows] = value; /* recording twice in a step keeps the last value */
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsRecordText(KergsResults res, const char name[], const char value[])
{
  PetscInt  j;
  PetscBool same = PETSC_FALSE;

  PetscFunctionBeginUser;
  for (j = 0; j < res->ntexts && !same; j++) PetscCall(PetscStrcmp(res->textname[j], name, &same));
  if (same)
    j--;
  else {
    PetscCheck(res->ntexts < KERGS_RESULTS_MAXTEXTS, res->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "Too many texts (at most %d) when adding \"%s\" to %s", KERGS_RESULTS_MAXTEXTS, name, res->path);
    PetscCheck(name[0] && strlen(name) < sizeof(res->textname[0]) && !strchr(name, '/'), res->comm, PETSC_ERR_ARG_WRONG,
               "Text name \"%s\" must be non-empty, shorter than %d characters and without '/'", name, (int)sizeof(res->textname[0]));
    j = res->ntexts++;
    PetscCall(PetscStrncpy(res->textname[j], name, sizeof(res->textname[0])));
  }
  PetscCall(PetscStrncpy(res->textvalue[j], value, sizeof(res->textvalue[0])));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsGetStatistic(KergsResults res, const char name[], PetscInt row, PetscReal *value, PetscBool *found)
{
  PetscBool same = PETSC_FALSE;

  PetscFunctionBeginUser;
  *value = PETSC_MAX_REAL;
  if (row < 0) row = res->nrows - 1;
  for (PetscInt j = 0; j < res->nstats && !same; j++) {
    PetscCall(PetscStrcmp(res->statname[j], name, &same));
    if (same && row >= 0 && row < res->nrows) *value = res->statvalues[j][row];
  }
  if (found) *found = (PetscBool)(*value != PETSC_MAX_REAL);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsGetNumRows(KergsResults res, PetscInt *nrows)
{
  PetscFunctionBeginUser;
  *nrows = res->nrows;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsGetPath(KergsResults res, const char **path, PetscBool *enabled)
{
  PetscFunctionBeginUser;
  if (path) *path = res->path;
  if (enabled) *enabled = res->enabled;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsEndStep(KergsResults res)
{
  PetscFunctionBeginUser;
  PetscCall(ResultsReserveRow(res, res->nrows + 1));
  res->nrows++;
  PetscFunctionReturn(0);
}

/* Whether the current (not yet ended) row holds any value. */
static PetscBool ResultsPendingRow(KergsResults res)
{
  for (PetscInt j = 0; j < res->nstats; j++)
    if (!PetscIsNanReal(res->statvalues[j][res->nrows])) return PETSC_TRUE;
  return PETSC_FALSE;
}

/* /stats/<name>: a Vec of global length nrows held entirely by rank 0, so the dataset is 1-D. */
static PetscErrorCode ResultsWriteStats(KergsResults res)
{
  PetscMPIInt rank;
  Vec         col;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(res->comm, &rank));
  PetscCall(VecCreateMPI(res->comm, rank == 0 ? res->nrows : 0, res->nrows, &col));
  PetscCall(PetscViewerHDF5PushGroup(res->viewer, "/stats"));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "nrows", PETSC_INT, &res->nrows));
  for (PetscInt j = 0; j < res->ntexts; j++)
    PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, res->textname[j], PETSC_STRING, res->textvalue[j]));
  for (PetscInt j = 0; j < res->nstats; j++) {
    PetscScalar *a;
    PetscCall(VecGetArray(col, &a));
    if (rank == 0)
      for (PetscInt i = 0; i < res->nrows; i++) a[i] = res->statvalues[j][i];
    PetscCall(VecRestoreArray(col, &a));
    PetscCall(PetscObjectSetName((PetscObject)col, res->statname[j]));
    PetscCall(VecView(col, res->viewer));
  }
  PetscCall(PetscViewerHDF5PopGroup(res->viewer));
  PetscCall(VecDestroy(&col));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsClose(KergsResults res)
{
  PetscFunctionBeginUser;
  if (!res->enabled || !res->viewer) PetscFunctionReturn(0);
  if (res->nalloc && ResultsPendingRow(res)) PetscCall(KergsResultsEndStep(res));
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(ResultsWriteStats(res));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "nsnapshots", PETSC_INT, &res->nsnapshots));
  PetscCall(PetscViewerDestroy(&res->viewer));
  PetscCall(KergsFileCommit(res->comm, res->tmppath, res->path));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsDestroy(KergsResults *res)
{
  PetscFunctionBeginUser;
  if (!*res) PetscFunctionReturn(0);
  /* Not closed: the temporary file stays as it is, never renamed to the final name. */
  PetscCall(PetscViewerDestroy(&(*res)->viewer));
  for (PetscInt j = 0; j < (*res)->nstats; j++) PetscCall(PetscFree((*res)->statvalues[j]));
  PetscCall(PetscFree(*res));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------
   Snapshots */

PetscErrorCode KergsResultsSnapshotDue(KergsResults res, PetscInt step, PetscBool last, PetscBool *due)
{
  PetscFunctionBeginUser;
  *due = PETSC_FALSE;
  if (!res->enabled) PetscFunctionReturn(0);
  if (res->nsnapshots == 0 || last) *due = PETSC_TRUE;
  if (res->snapshot_every > 0 && step % res->snapshot_every == 0) *due = PETSC_TRUE;
  if (step == res->last_snapshot_step) *due = PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* A Vec of nlocal blocks of bs reals on this rank, named, viewed into the current group, destroyed.
   values holds the nlocal * bs local entries (NULL when nlocal is 0). */
PetscErrorCode KergsViewBlocks(PetscViewer viewer, MPI_Comm comm, const char name[], PetscInt nlocal, PetscInt bs, const PetscReal *values)
{
  Vec          vec;
  PetscScalar *a;

  PetscFunctionBeginUser;
  PetscCall(VecCreate(comm, &vec));
  PetscCall(VecSetSizes(vec, nlocal * bs, PETSC_DETERMINE));
  PetscCall(VecSetBlockSize(vec, bs));
  PetscCall(VecSetType(vec, VECMPI));
  PetscCall(VecGetArray(vec, &a));
  for (PetscInt i = 0; i < nlocal * bs; i++) a[i] = values[i];
  PetscCall(VecRestoreArray(vec, &a));
  PetscCall(PetscObjectSetName((PetscObject)vec, name));
  PetscCall(VecView(vec, viewer));
  PetscCall(VecDestroy(&vec));
  PetscFunctionReturn(0);
}

/* Integer fields are stored as reals (exact up to 2^53). */
PetscErrorCode KergsViewIntegers(PetscViewer viewer, MPI_Comm comm, const char name[], PetscInt nlocal, const PetscInt *values)
{
  PetscReal *r;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(nlocal, &r));
  for (PetscInt i = 0; i < nlocal; i++) r[i] = (PetscReal)values[i];
  PetscCall(KergsViewBlocks(viewer, comm, name, nlocal, 1, r));
  PetscCall(PetscFree(r));
  PetscFunctionReturn(0);
}

/* The owned disks of each rank (global indices [dstart, dend)), in rank order: the datasets are in global-index
   order. */
static PetscErrorCode SnapshotDisks(PetscViewer viewer, KergsScene scene)
{
  KergsDisks D;
  MPI_Comm   sccomm;
  PetscInt   s, n, nsum;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetComm(scene, &sccomm));
  s = D.dstart;
  n = D.nowned;
  PetscCheck(0 <= s && s <= D.dend && D.dend <= D.ndisks && n == D.dend - s, sccomm, PETSC_ERR_ARG_OUTOFRANGE,
             "Scene disk range [%" PetscInt_FMT ", %" PetscInt_FMT ") is not within the %" PetscInt_FMT " disks", s, D.dend, D.ndisks);
  PetscCall(MPIU_Allreduce(&n, &nsum, 1, MPIU_INT, MPI_SUM, sccomm));
  PetscCheck(nsum == D.ndisks, sccomm, PETSC_ERR_ARG_WRONG,
             "Scene disk ranges cover %" PetscInt_FMT " disks, not the %" PetscInt_FMT " of the scene", nsum, D.ndisks);
  PetscCall(KergsViewIntegers(viewer, sccomm, "id", n, D.id));
  PetscCall(KergsViewBlocks(viewer, sccomm, "x", n, KERGS_DIM, D.x));
  PetscCall(KergsViewBlocks(viewer, sccomm, "v", n, KERGS_DIM, D.v));
  PetscCall(KergsViewBlocks(viewer, sccomm, "rot", n, KERGS_NROT, D.rot));
  PetscCall(KergsViewBlocks(viewer, sccomm, "omega", n, KERGS_NROT, D.omega));
  PetscCall(KergsViewBlocks(viewer, sccomm, "radius", n, 1, D.radius));
  PetscCall(KergsViewIntegers(viewer, sccomm, "material", n, D.material));
  PetscFunctionReturn(0);
}

/* walls (nwalls x 2*KERGS_DIM: a then b) and wall_infinite (0 segment, 1 line), written by rank 0. */
static PetscErrorCode SnapshotWalls(PetscViewer viewer, KergsScene scene)
{
  MPI_Comm         sccomm;
  PetscInt         scnwalls;
  const KergsWall *scwalls;
  PetscMPIInt      rank;
  PetscInt         n;
  PetscReal       *ab, *inf;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetComm(scene, &sccomm));
  PetscCall(KergsSceneGetWalls(scene, &scnwalls, &scwalls));
  PetscCallMPI(MPI_Comm_rank(sccomm, &rank));
  n = rank == 0 ? scnwalls : 0;
  PetscCall(PetscMalloc2(n * KERGS_WALL_COLUMNS, &ab, n, &inf));
  for (PetscInt w = 0; w < n; w++) {
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      ab[w * KERGS_WALL_COLUMNS + d]             = scwalls[w].a[d];
      ab[w * KERGS_WALL_COLUMNS + KERGS_DIM + d] = scwalls[w].b[d];
    }
    inf[w] = scwalls[w].infinite ? 1.0 : 0.0;
  }
  PetscCall(KergsViewBlocks(viewer, sccomm, "walls", n, KERGS_WALL_COLUMNS, ab));
  PetscCall(KergsViewBlocks(viewer, sccomm, "wall_infinite", n, 1, inf));
  PetscCall(PetscFree2(ab, inf));
  PetscFunctionReturn(0);
}

/* This rank's contacts: a, b (global disk indices, as in the snapshot's disk datasets; b a wall index when kind is
   1), kind, n, gap, r. The tangential impulse is 0 in frictionless scenes. */
static PetscErrorCode SnapshotContacts(PetscViewer viewer, KergsScene scene, KergsContacts contacts)
{
  PetscInt      m   = 0;
  KergsContact *cts = NULL;
  KergsDisks    D;
  MPI_Comm      comm;
  PetscBool     scfrictional;
  PetscInt     *a, *b, *kind;
  PetscReal    *nrm, *gap, *r;

  PetscFunctionBeginUser;
  if (contacts) PetscCall(KergsContactsGetLocal(contacts, &m, &cts));
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(KergsSceneGetModel(scene, &scfrictional, NULL));
  PetscCall(PetscMalloc6(m, &a, m, &b, m, &kind, m * KERGS_DIM, &nrm, m, &gap, m * KERGS_MAXCOMP, &r));
  for (PetscInt k = 0; k < m; k++) {
    const KergsContact *c = &cts[k];
    a[k]                  = D.gidx[c->a];
    b[k]                  = c->kind == KERGS_CONTACT_DISK_DISK ? D.gidx[c->b] : c->b;
    kind[k]               = c->kind == KERGS_CONTACT_DISK_WALL ? 1 : 0;
    gap[k]                = c->gap;
    for (PetscInt d = 0; d < KERGS_DIM; d++) nrm[k * KERGS_DIM + d] = c->n[d];
    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) r[k * KERGS_MAXCOMP + j] = (j == 0 || scfrictional) ? c->r[j] : 0.0;
  }
  PetscCall(KergsViewIntegers(viewer, comm, "a", m, a));
  PetscCall(KergsViewIntegers(viewer, comm, "b", m, b));
  PetscCall(KergsViewIntegers(viewer, comm, "kind", m, kind));
  PetscCall(KergsViewBlocks(viewer, comm, "n", m, KERGS_DIM, nrm));
  PetscCall(KergsViewBlocks(viewer, comm, "gap", m, 1, gap));
  PetscCall(KergsViewBlocks(viewer, comm, "r", m, KERGS_MAXCOMP, r));
  PetscCall(PetscFree6(a, b, kind, nrm, gap, r));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsSnapshot(KergsResults res, KergsScene scene, KergsContacts contacts)
{
  KergsDisks D;
  PetscInt   scstep, scnwalls;
  PetscReal  sctime;
  char       group[64];
  PetscInt   ncontacts, nlocal = 0;

  PetscFunctionBeginUser;
  if (contacts) PetscCall(KergsContactsGetLocal(contacts, &nlocal, NULL));
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetStep(scene, &scstep, &sctime, NULL));
  PetscCall(KergsSceneGetWalls(scene, &scnwalls, NULL));
  if (!res->enabled) PetscFunctionReturn(0);
  PetscCheck(res->viewer, res->comm, PETSC_ERR_ORDER, "Results file %s is not open: call KergsResultsOpen() before KergsResultsSnapshot()",
             res->path[0] ? res->path : "(unnamed)");
  if (scstep == res->last_snapshot_step) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(MPIU_Allreduce(&nlocal, &ncontacts, 1, MPIU_INT, MPI_SUM, res->comm));
  PetscCall(PetscSNPrintf(group, sizeof(group), "/snapshots/%06" PetscInt_FMT, res->nsnapshots));
  PetscCall(PetscViewerHDF5PushGroup(res->viewer, group));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "step", PETSC_INT, &scstep));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "time", PETSC_REAL, &sctime));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "ndisks", PETSC_INT, &D.ndisks));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "nwalls", PETSC_INT, &scnwalls));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "ncontacts", PETSC_INT, &ncontacts));
  PetscCall(SnapshotDisks(res->viewer, scene));
  PetscCall(SnapshotWalls(res->viewer, scene));
  PetscCall(SnapshotContacts(res->viewer, scene, contacts));
  PetscCall(PetscViewerHDF5PopGroup(res->viewer));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  res->nsnapshots++;
  res->last_snapshot_step = scstep;
  PetscFunctionReturn(0);
}
