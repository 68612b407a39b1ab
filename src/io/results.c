/* kergs results: one HDF5 file per run (statistics per step and snapshots of the packing), written through
   PetscViewerHDF5 to "<path>.tmp" and renamed to <path> only once complete, so a file under its final name is always
   complete. The statistics are appended to chunked, extendible datasets as the run goes and the file is flushed to
   disk regularly, so that the .tmp of a killed run is a readable file holding every flushed row and snapshot. The
   layout is documented in docs/results.md. */
#include <kergs/private/resultsimpl.h>
#include <kergs/private/h5probe.h>
#include <kergs/xdmf.h>
#include <petscviewerhdf5.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#define KERGS_RESULTS_INITIAL_ROWS 64
#define KERGS_RESULTS_CHUNK 256                /* rows per chunk of a /stats dataset (2 KB) */
#define KERGS_RESULTS_OVERHEAD 65536.0         /* bytes of HDF5 metadata allowed for per write, in the free space checks */
#define KERGS_WALL_COLUMNS (2 * KERGS_DIM)     /* a and b endpoints */
#define KERGS_RESULTS_FORMAT "kergs results 1" /* root attribute kergs_format */

/* PETSc's viewer has no call that appends rows to a 1-D dataset: /stats is written through the viewer's HDF5 file
   (PetscViewerHDF5GetFileId) with these checked calls. */
#define CallHDF5(call) PetscCheck((call) >= 0, PETSC_COMM_SELF, PETSC_ERR_LIB, "HDF5 call failed: %s", #call)

static void FillNaN(PetscReal *a, PetscInt from, PetscInt to)
{
  for (PetscInt i = from; i < to; i++) a[i] = (PetscReal)NAN;
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
  (*res)->flush_every        = 1000;
  (*res)->flush_seconds      = 5.0;
  (*res)->xdmf               = PETSC_TRUE;
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
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-output_every", "Snapshot every N steps (0: only the first and the last step)",
                            "KergsResultsSnapshotDue", res->snapshot_every, &res->snapshot_every, NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-output_none", "Write no results file", "KergsResultsSetFromOptions", none, &none, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-output_flush_every",
                            "Write the statistics to the results file and flush it to disk every N steps (0: not by steps); a killed "
                            "run's <path>.tmp holds every flushed step",
                            "KergsResultsFlush", res->flush_every, &res->flush_every, NULL));
  PetscCall(PetscOptionsReal("-output_flush_seconds", "Also flush the results file to disk every T seconds of wall time (0: not by time)",
                             "KergsResultsFlush", res->flush_seconds, &res->flush_seconds, NULL));
  PetscCall(
      KergsOptionsBool(PetscOptionsObject, "-output_xdmf",
                       "Write <output without .h5>.xdmf beside the results file: its snapshots as a time series for ParaView's XDMF Reader",
                       "KergsXdmfWrite", res->xdmf, &res->xdmf, NULL));
  PetscOptionsEnd();
  PetscCheck(res->snapshot_every >= 0, res->comm, PETSC_ERR_ARG_OUTOFRANGE, "Option -output_every must be >= 0, got %" PetscInt_FMT,
             res->snapshot_every);
  PetscCheck(res->flush_every >= 0, res->comm, PETSC_ERR_ARG_OUTOFRANGE, "Option -output_flush_every must be >= 0, got %" PetscInt_FMT,
             res->flush_every);
  PetscCheck(res->flush_seconds >= 0 && !PetscIsInfOrNanReal(res->flush_seconds), res->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Option -output_flush_seconds must be a non-negative number of seconds, got %g", (double)res->flush_seconds);
  PetscCheck(!set || path[0], res->comm, PETSC_ERR_ARG_WRONG, "Option -output needs a file name (use -output_none for no results file)");
  res->enabled = (PetscBool)!none;
  if (!res->path[0]) PetscCall(ResultsDefaultPath(res, res->path, sizeof(res->path)));
  if (res->enabled && res->xdmf) {
    const char *slash = strrchr(res->path, '/');
    PetscCheck(!strchr(slash ? slash + 1 : res->path, ':'), res->comm, PETSC_ERR_ARG_WRONG,
               "The results file name %s contains ':', which an XDMF file cannot reference (XDMF separates the file from the dataset "
               "with ':'): rename it, or give -output_xdmf false",
               res->path);
    PetscCall(KergsXdmfPath(res->path, res->xdmfpath, sizeof(res->xdmfpath)));
  } else
    res->xdmfpath[0] = 0;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsGetState(KergsResults res, KergsResultsState *state)
{
  PetscFunctionBeginUser;
  state->nrows              = res->nrows;
  state->nsnapshots         = res->nsnapshots;
  state->last_snapshot_step = res->last_snapshot_step;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsSetContinue(KergsResults res, const char source[], const KergsResultsState *state, PetscInt step)
{
  PetscFunctionBeginUser;
  PetscCheck(!res->viewer, res->comm, PETSC_ERR_ORDER, "KergsResultsSetContinue() must come before KergsResultsOpen()");
  PetscCall(PetscStrncpy(res->source, source ? source : "", sizeof(res->source)));
  res->source_state = *state;
  res->source_step  = step;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsSetEnd(KergsResults res, const char end[])
{
  PetscFunctionBeginUser;
  PetscCall(PetscStrncpy(res->end, end, sizeof(res->end)));
  PetscFunctionReturn(0);
}

/* Root attributes saying where the data came from (docs/results.md): prefix "" for the run that created the file,
   "restart_" for the latest restart that continued it. */
static PetscErrorCode WriteProvenance(KergsResults res, const char prefix[])
{
  KergsProvenance prov;
  const char     *names[4] = {"kergs_version", "options", "ranks", "date"};
  char            name[64];
  PetscInt        ranks;

  PetscFunctionBeginUser;
  PetscCall(KergsProvenanceGet(res->comm, &prov));
  ranks = prov.ranks;
  for (PetscInt k = 0; k < 4; k++) {
    PetscCall(PetscSNPrintf(name, sizeof(name), "%s%s", prefix, names[k]));
    if (k == 2)
      PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", name, PETSC_INT, &ranks));
    else
      PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", name, PETSC_STRING,
                                              k == 0   ? prov.version
                                              : k == 1 ? prov.options
                                                       : prov.date));
  }
  PetscCall(KergsProvenanceDestroy(&prov));
  PetscFunctionReturn(0);
}

static PetscErrorCode OpenNew(KergsResults res)
{
  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5Open(res->comm, res->tmppath, FILE_MODE_WRITE, &res->viewer));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "kergs_format", PETSC_STRING, KERGS_RESULTS_FORMAT));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "dim", PETSC_INT, &(PetscInt){KERGS_DIM}));
  PetscCall(WriteProvenance(res, ""));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "nsnapshots", PETSC_INT, &(PetscInt){0}));
  res->nsnapshots         = 0;
  res->last_snapshot_step = -1;
  res->nflushed           = 0;
  res->xdmf_written       = 0;
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------
   The snapshots' attributes, kept for the XDMF file */

/* Keep the attributes of snapshot k (capacity doubles). */
static PetscErrorCode ResultsKeepSnapshot(KergsResults res, PetscInt k, const KergsXdmfSnapshot *s)
{
  PetscFunctionBeginUser;
  if (k >= res->nsnapalloc) {
    KergsXdmfSnapshot *grown;
    PetscInt           nalloc = PetscMax(2 * res->nsnapalloc, 16);
    while (nalloc <= k) nalloc *= 2;
    PetscCall(PetscMalloc1(nalloc, &grown));
    if (res->nsnapalloc) PetscCall(PetscArraycpy(grown, res->snaps, res->nsnapalloc));
    PetscCall(PetscFree(res->snaps));
    res->snaps      = grown;
    res->nsnapalloc = nalloc;
  }
  res->snaps[k] = *s;
  PetscFunctionReturn(0);
}

/* The attributes of snapshot group k of an open file (every rank reads them: a continued file's earlier snapshots). */
static PetscErrorCode ResultsReadSnapshot(hid_t file, PetscInt k, KergsXdmfSnapshot *s)
{
  const char *names[5] = {"step", "time", "ndisks", "nwalls", "ncontacts"};
  const hid_t itype    = sizeof(PetscInt) == 8 ? H5T_NATIVE_LLONG : H5T_NATIVE_INT;
  void       *dest[5]  = {&s->step, &s->time, &s->ndisks, &s->nwalls, &s->ncontacts};
  char        group[64];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(group, sizeof(group), "/snapshots/%06" PetscInt_FMT, k));
  for (int j = 0; j < 5; j++) {
    hid_t a = H5Aopen_by_name(file, group, names[j], H5P_DEFAULT, H5P_DEFAULT);
    PetscCheck(a >= 0, PETSC_COMM_SELF, PETSC_ERR_FILE_UNEXPECTED, "Results file: snapshot %s has no attribute %s", group, names[j]);
    CallHDF5(H5Aread(a, j == 1 ? H5T_NATIVE_DOUBLE : itype, dest[j]));
    CallHDF5(H5Aclose(a));
  }
  PetscFunctionReturn(0);
}

/* Rank 0 rewrites the XDMF file (-output_xdmf) when snapshots were added since it was last written: the first time at
   once, then at most every -output_flush_seconds (at every call with 0) and every 20 times the last rewrite's duration
   (each rewrite writes the whole list, about 50 us per snapshot here: this keeps its cost under 5 % of the run), and
   always when `now` is set. It references the file under the name it has now: the .tmp while the run goes, the final
   name once closed. Not before a step's row is flushed: a run refused at its first detection (grains that overlap)
   leaves the XDMF of an earlier run under that name as it was. */
static PetscErrorCode ResultsRefreshXdmf(KergsResults res, PetscBool now, PetscBool final)
{
  PetscMPIInt    rank;
  PetscLogDouble t, done;
  const char    *h5 = final ? res->path : res->tmppath, *slash = strrchr(h5, '/');

  PetscFunctionBeginUser;
  if (!res->enabled || !res->xdmf || (!final && res->nflushed == 0)) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_rank(res->comm, &rank));
  if (rank != 0) PetscFunctionReturn(0);
  PetscCall(PetscTime(&t));
  if (!now && (res->nsnapshots == res->xdmf_written ||
               (res->xdmf_written > 0 && t - res->last_xdmf < PetscMax((PetscLogDouble)res->flush_seconds, 20 * res->xdmf_cost))))
    PetscFunctionReturn(0);
  PetscCall(KergsXdmfWrite(res->xdmfpath, slash ? slash + 1 : h5, res->nsnapshots, res->snaps));
  PetscCall(PetscTime(&done));
  res->xdmf_written = res->nsnapshots;
  res->last_xdmf    = t;
  res->xdmf_cost    = done - t;
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------
   Continuing a checkpointed run's file */

/* Rank 0: whether file holds the checkpoint's rows and snapshots (why is empty when it does). Opened read-only with
   HDF5's error printing off: a damaged file is an expected outcome here. */
static void ProbeSource(const char file[], const KergsResultsState *st, PetscInt step, char why[], size_t len)
{
  KergsH5Quiet quiet;
  hid_t        f, a, d, space;
  hsize_t      dims[1] = {0}, start[1], count[1] = {1};
  PetscInt     nsnap = -1;
  double       last  = -1;

  why[0] = 0;
  KergsH5QuietBegin(&quiet);
  f = H5Fopen(file, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) snprintf(why, len, "not a readable HDF5 file (damaged?)");
  if (!why[0] && !KergsH5HasFormat(f, KERGS_RESULTS_FORMAT)) snprintf(why, len, "not a kergs results file");
  if (!why[0]) {
    a = H5Aopen_by_name(f, "/", "nsnapshots", H5P_DEFAULT, H5P_DEFAULT);
    if (a < 0 || H5Aread(a, sizeof(PetscInt) == 8 ? H5T_NATIVE_LLONG : H5T_NATIVE_INT, &nsnap) < 0 || nsnap < st->nsnapshots)
      snprintf(why, len, "holds %d snapshots, the checkpoint needs %d", (int)nsnap, (int)st->nsnapshots);
    if (a >= 0) (void)H5Aclose(a);
  }
  if (!why[0] && st->nrows > 0) {
    d     = H5Dopen2(f, "/stats/step", H5P_DEFAULT);
    space = d >= 0 ? H5Dget_space(d) : -1;
    if (space < 0 || H5Sget_simple_extent_dims(space, dims, NULL) != 1 || dims[0] < (hsize_t)st->nrows)
      snprintf(why, len, "holds %d rows of statistics, the checkpoint needs %d", (int)dims[0], (int)st->nrows);
    else {
      hid_t mem = H5Screate_simple(1, count, NULL);
      start[0]  = (hsize_t)st->nrows - 1;
      (void)H5Sselect_hyperslab(space, H5S_SELECT_SET, start, NULL, count, NULL);
      if (H5Dread(d, H5T_NATIVE_DOUBLE, mem, space, H5P_DEFAULT, &last) < 0 || last != (double)step)
        snprintf(why, len, "row %d of its statistics is step %g, not the checkpoint's step %d", (int)st->nrows, last, (int)step);
      (void)H5Sclose(mem);
    }
    if (space >= 0) (void)H5Sclose(space);
    if (d >= 0) (void)H5Dclose(d);
  }
  if (f >= 0) (void)H5Fclose(f);
  KergsH5QuietEnd(&quiet);
}

/* H5Literate callback: the names of the datasets of /stats. */
#if H5_VERSION_GE(1, 12, 0)
typedef H5L_info2_t LinkInfo;
#else
typedef H5L_info_t LinkInfo;
#endif
static herr_t CollectName(hid_t group, const char *name, const LinkInfo *info, void *ctx)
{
  KergsResults res = (KergsResults)ctx;

  (void)group;
  (void)info;
  if (res->nstats >= KERGS_RESULTS_MAXSTATS || strlen(name) >= sizeof(res->statname[0])) return -1;
  snprintf(res->statname[res->nstats++], sizeof(res->statname[0]), "%s", name);
  return 0;
}

/* H5Literate callback: counts the links of a group. */
static herr_t CountLinks(hid_t group, const char *name, const LinkInfo *info, void *ctx)
{
  (void)group;
  (void)name;
  (void)info;
  (*(hsize_t *)ctx)++;
  return 0;
}

/* The file continues: its /stats cut to the checkpoint's rows and adopted as the columns, later snapshots dropped. */
static PetscErrorCode TrimToCheckpoint(KergsResults res)
{
  const KergsResultsState *st = &res->source_state;
  hid_t                    file, group;
  hsize_t                  n = (hsize_t)st->nrows, idx = 0;
  PetscInt                 filesnap = 0;
  char                     name[64];
  htri_t                   has;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5GetFileId(res->viewer, &file));
  for (PetscInt j = 0; j < res->nstats; j++) PetscCall(PetscFree(res->statvalues[j]));
  res->nstats = res->nalloc = 0;
  has                       = H5Lexists(file, "/stats", H5P_DEFAULT);
  CallHDF5(has);
  if (has > 0) {
    group = H5Gopen2(file, "/stats", H5P_DEFAULT);
    CallHDF5(group);
    CallHDF5(H5Literate(group, H5_INDEX_NAME, H5_ITER_INC, &idx, CollectName, res));
    res->nalloc = KERGS_RESULTS_INITIAL_ROWS;
    for (PetscInt j = 0; j < res->nstats; j++) {
      PetscCall(PetscMalloc1(res->nalloc, &res->statvalues[j]));
      FillNaN(res->statvalues[j], 0, res->nalloc);
    }
    for (PetscInt j = 0; j < res->nstats; j++) {
      hid_t d = H5Dopen2(group, res->statname[j], H5P_DEFAULT);
      CallHDF5(d);
      CallHDF5(H5Dset_extent(d, &n));
      CallHDF5(H5Dclose(d));
    }
    CallHDF5(H5Gclose(group));
  }
  /* every group from the checkpoint's count on: later snapshots, and one a kill interrupted (beyond the attribute) */
  has = H5Lexists(file, "/snapshots", H5P_DEFAULT);
  CallHDF5(has);
  if (has > 0) {
    hsize_t count = 0;
    idx           = 0;
    group         = H5Gopen2(file, "/snapshots", H5P_DEFAULT);
    CallHDF5(group);
    CallHDF5(H5Literate(group, H5_INDEX_NAME, H5_ITER_INC, &idx, CountLinks, &count));
    CallHDF5(H5Gclose(group));
    filesnap = (PetscInt)count;
  }
  for (PetscInt k = st->nsnapshots; k < filesnap + 1; k++) { /* names are 0 .. count - 1 unless one is missing: one more */
    PetscCall(PetscSNPrintf(name, sizeof(name), "/snapshots/%06" PetscInt_FMT, k));
    has = H5Lexists(file, name, H5P_DEFAULT);
    if (has > 0) CallHDF5(H5Ldelete(file, name, H5P_DEFAULT));
  }
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "nsnapshots", PETSC_INT, &st->nsnapshots));
  for (PetscInt k = 0; k < st->nsnapshots; k++) {
    KergsXdmfSnapshot s;
    PetscCall(ResultsReadSnapshot(file, k, &s));
    PetscCall(ResultsKeepSnapshot(res, k, &s));
  }
  res->xdmf_written = 0;
  res->nrows = res->row0 = res->nflushed = st->nrows;
  res->nsnapshots                        = st->nsnapshots;
  res->last_snapshot_step                = st->last_snapshot_step;
  PetscFunctionReturn(0);
}

static PetscErrorCode OpenContinue(KergsResults res)
{
  char        cand[2][PETSC_MAX_PATH_LEN + 8], why[2][256] = {"", ""}, msg[3 * PETSC_MAX_PATH_LEN] = "";
  int         mode = 0, chosen = -1; /* mode 0: a new file, 1: continue chosen in place, 2: copy chosen to tmppath */
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(res->comm, &rank));
  PetscCall(PetscSNPrintf(cand[0], sizeof(cand[0]), "%s.tmp", res->source));
  PetscCall(PetscSNPrintf(cand[1], sizeof(cand[1]), "%s", res->source));
  if (rank == 0) {
    PetscBool exists[2];
    for (int c = 0; c < 2 && chosen < 0; c++) {
      PetscCall(PetscTestFile(cand[c], '\0', &exists[c]));
      if (!exists[c]) continue;
      ProbeSource(cand[c], &res->source_state, res->source_step, why[c], sizeof(why[c]));
      if (!why[c][0]) chosen = c;
    }
    if (chosen >= 0) {
      PetscBool same;
      PetscCall(PetscStrcmp(cand[chosen], res->tmppath, &same));
      mode = same ? 1 : 2;
    } else if (exists[0] || exists[1])
      PetscCall(PetscSNPrintf(msg, sizeof(msg),
                              "Cannot continue the results of the checkpointed run: %s%s%s%s%s%s%s. Move it away to start a new "
                              "results file at the restart, or restart from the checkpoint that matches it",
                              exists[0] ? cand[0] : "", exists[0] ? ": " : "", exists[0] ? why[0] : "", exists[0] && exists[1] ? "; " : "",
                              exists[1] ? cand[1] : "", exists[1] ? ": " : "", exists[1] ? why[1] : ""));
  }
  PetscCallMPI(MPI_Bcast(msg, (int)sizeof(msg), MPI_CHAR, 0, res->comm));
  PetscCheck(!msg[0], res->comm, PETSC_ERR_FILE_UNEXPECTED, "%s", msg);
  PetscCallMPI(MPI_Bcast(&mode, 1, MPI_INT, 0, res->comm));
  PetscCallMPI(MPI_Bcast(&chosen, 1, MPI_INT, 0, res->comm));
  if (mode == 0) {
    PetscCall(PetscPrintf(res->comm, "kergs: results file %s of the checkpointed run not found: %s begins at the restart\n", res->source,
                          res->path));
    PetscCall(OpenNew(res));
    res->nrows = res->row0 = res->nflushed = 0;
    for (PetscInt j = 0; j < res->nstats; j++) PetscCall(PetscFree(res->statvalues[j]));
    res->nstats = res->nalloc = 0;
    PetscFunctionReturn(0);
  }
  if (mode == 2) PetscCall(KergsFileCopy(res->comm, cand[chosen], res->tmppath));
  PetscCall(PetscViewerHDF5Open(res->comm, res->tmppath, FILE_MODE_APPEND, &res->viewer));
  PetscCall(TrimToCheckpoint(res));
  PetscCall(WriteProvenance(res, "restart_"));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "restart_step", PETSC_INT, &res->source_step));
  res->continued = PETSC_TRUE;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsOpen(KergsResults res)
{
  PetscFunctionBeginUser;
  if (!res->enabled) PetscFunctionReturn(0);
  PetscCheck(!res->viewer, res->comm, PETSC_ERR_ORDER, "Results file %s is already open", res->tmppath);
  if (!res->path[0]) PetscCall(ResultsDefaultPath(res, res->path, sizeof(res->path)));
  if (res->xdmf && !res->xdmfpath[0]) PetscCall(KergsXdmfPath(res->path, res->xdmfpath, sizeof(res->xdmfpath)));
  PetscCall(PetscSNPrintf(res->tmppath, sizeof(res->tmppath), "%s.tmp", res->path));
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(KergsFileMakeParentDir(res->comm, res->path));
  if (res->source[0])
    PetscCall(OpenContinue(res));
  else
    PetscCall(OpenNew(res));
  PetscCall(PetscViewerHDF5SetBaseDimension2(res->viewer, PETSC_FALSE)); /* the documented layout: 1-D scalars, float64 */
  PetscCall(PetscViewerHDF5SetSPOutput(res->viewer, PETSC_FALSE));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "complete", PETSC_INT, &(PetscInt){0}));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscCall(PetscTime(&res->last_flush));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------
   Statistics: a table kept on every rank, one column per name, rows [row0, nrows] in memory. Unset cells are NaN. */

/* Make room for row `row` (>= row0) in every column (capacity doubles). */
static PetscErrorCode ResultsReserveRow(KergsResults res, PetscInt row)
{
  PetscInt nalloc = res->nalloc ? res->nalloc : KERGS_RESULTS_INITIAL_ROWS;

  PetscFunctionBeginUser;
  if (row - res->row0 < res->nalloc) PetscFunctionReturn(0);
  while (nalloc <= row - res->row0) nalloc *= 2;
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
      PetscCall(ResultsReserveRow(res, res->nrows));
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
  res->statvalues[col][res->nrows - res->row0] = value; /* recording twice in a step keeps the last value */
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsRecordText(KergsResults res, const char name[], const char value[])
{
  PetscFunctionBeginUser;
  PetscCall(KergsResultsRecordStatisticText(res, NULL, name, value));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsRecordStatisticText(KergsResults res, const char stat[], const char name[], const char value[])
{
  PetscInt  j;
  PetscBool same = PETSC_FALSE;

  PetscFunctionBeginUser;
  if (!stat) stat = "";
  for (j = 0; j < res->ntexts && !same; j++) {
    PetscCall(PetscStrcmp(res->textname[j], name, &same));
    if (same) PetscCall(PetscStrcmp(res->textstat[j], stat, &same));
  }
  if (same)
    j--;
  else {
    PetscCheck(res->ntexts < KERGS_RESULTS_MAXTEXTS, res->comm, PETSC_ERR_ARG_OUTOFRANGE,
               "Too many texts (at most %d) when adding \"%s\" to %s", KERGS_RESULTS_MAXTEXTS, name, res->path);
    PetscCheck(name[0] && strlen(name) < sizeof(res->textname[0]) && !strchr(name, '/'), res->comm, PETSC_ERR_ARG_WRONG,
               "Text name \"%s\" must be non-empty, shorter than %d characters and without '/'", name, (int)sizeof(res->textname[0]));
    PetscCheck(strlen(stat) < sizeof(res->textstat[0]), res->comm, PETSC_ERR_ARG_WRONG, "Statistic name \"%s\" is too long", stat);
    j = res->ntexts++;
    PetscCall(PetscStrncpy(res->textname[j], name, sizeof(res->textname[0])));
    PetscCall(PetscStrncpy(res->textstat[j], stat, sizeof(res->textstat[0])));
  }
  PetscCheck(strlen(value) < sizeof(res->textvalue[0]), res->comm, PETSC_ERR_ARG_WRONG, "Text \"%s\" is too long", name);
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
    if (same && row >= res->row0 && row < res->nrows) *value = res->statvalues[j][row - res->row0];
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

PetscErrorCode KergsResultsGetXdmfPath(KergsResults res, const char **path)
{
  PetscFunctionBeginUser;
  *path = res->enabled && res->xdmf ? res->xdmfpath : "";
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsGetPath(KergsResults res, const char **path, PetscBool *enabled)
{
  PetscFunctionBeginUser;
  if (path) *path = res->path;
  if (enabled) *enabled = res->enabled;
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------
   Writing: rows appended to /stats, flushes, and the handling of a failed write */

/* /stats/<name>: open, or create as an extendible 1-D float64 dataset of fill value NaN (the rows before a statistic
   existed, and rows where it was not recorded, read as NaN). */
static PetscErrorCode StatDataset(hid_t group, const char name[], hid_t *d)
{
  htri_t has = H5Lexists(group, name, H5P_DEFAULT);

  PetscFunctionBeginUser;
  CallHDF5(has);
  if (has > 0)
    *d = H5Dopen2(group, name, H5P_DEFAULT);
  else {
    const hsize_t zero[1] = {0}, unlimited[1] = {H5S_UNLIMITED}, chunk[1] = {KERGS_RESULTS_CHUNK};
    const double  nan   = (double)NAN;
    hid_t         space = H5Screate_simple(1, zero, unlimited), dcpl = H5Pcreate(H5P_DATASET_CREATE);
    CallHDF5(space);
    CallHDF5(dcpl);
    CallHDF5(H5Pset_chunk(dcpl, 1, chunk));
    CallHDF5(H5Pset_fill_value(dcpl, H5T_NATIVE_DOUBLE, &nan));
    CallHDF5(H5Pset_alloc_time(dcpl, H5D_ALLOC_TIME_EARLY)); /* chunks allocated collectively when the dataset grows */
    CallHDF5(H5Pset_fill_time(dcpl, H5D_FILL_TIME_ALLOC));
    *d = H5Dcreate2(group, name, H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    CallHDF5(H5Pclose(dcpl));
    CallHDF5(H5Sclose(space));
  }
  CallHDF5(*d);
  PetscFunctionReturn(0);
}

/* The completed rows not yet in the file, appended (rank 0 writes the values, every rank grows the datasets). */
static PetscErrorCode AppendRows(KergsResults res)
{
  const hsize_t n = (hsize_t)(res->nrows - res->nflushed), first = (hsize_t)res->nflushed, total = (hsize_t)res->nrows;
  PetscMPIInt   rank;
  hid_t         file, group;
  htri_t        has;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(res->comm, &rank));
  PetscCall(PetscViewerHDF5GetFileId(res->viewer, &file));
  has = H5Lexists(file, "/stats", H5P_DEFAULT);
  CallHDF5(has);
  group = has > 0 ? H5Gopen2(file, "/stats", H5P_DEFAULT) : H5Gcreate2(file, "/stats", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  CallHDF5(group);
  for (PetscInt j = 0; j < res->nstats; j++) {
    hid_t d;
    PetscCall(StatDataset(group, res->statname[j], &d));
    CallHDF5(H5Dset_extent(d, &total));
    if (rank == 0 && n > 0) {
      hid_t space = H5Dget_space(d), mem = H5Screate_simple(1, &n, NULL);
      CallHDF5(space);
      CallHDF5(mem);
      CallHDF5(H5Sselect_hyperslab(space, H5S_SELECT_SET, &first, NULL, &n, NULL));
      CallHDF5(H5Dwrite(d, H5T_NATIVE_DOUBLE, mem, space, H5P_DEFAULT, &res->statvalues[j][res->nflushed - res->row0]));
      CallHDF5(H5Sclose(mem));
      CallHDF5(H5Sclose(space));
    }
    CallHDF5(H5Dclose(d));
  }
  CallHDF5(H5Gclose(group));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/stats", "nrows", PETSC_INT, &res->nrows));
  for (PetscInt j = 0; j < res->ntexts; j++) {
    char parent[80];
    PetscCall(PetscSNPrintf(parent, sizeof(parent), "/stats%s%s", res->textstat[j][0] ? "/" : "", res->textstat[j]));
    PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, parent, res->textname[j], PETSC_STRING, res->textvalue[j]));
  }
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "nsnapshots", PETSC_INT, &res->nsnapshots));
  CallHDF5(H5Fflush(file, H5F_SCOPE_GLOBAL));
  PetscFunctionReturn(0);
}

/* Rows now in the file leave memory, except the last completed one (KergsResultsGetStatistic(-1)) and the current. */
static void DropFlushedRows(KergsResults res)
{
  const PetscInt keep = PetscMax(res->nrows - 1, 0), shift = keep - res->row0;

  if (shift <= 0) return;
  for (PetscInt j = 0; j < res->nstats; j++) {
    for (PetscInt i = 0; i + shift < res->nalloc; i++) res->statvalues[j][i] = res->statvalues[j][i + shift];
    FillNaN(res->statvalues[j], res->nalloc - shift, res->nalloc);
  }
  res->row0 = keep;
}

/* Run a write on the open file; if it fails on this rank, the partial .tmp is removed and the error says whether the
   disk was full (KergsFileWriteFailed). */
static PetscErrorCode Guarded(KergsResults res, PetscErrorCode (*write)(KergsResults, void *), void *ctx, const char what[])
{
  PetscErrorCode ierr;

  PetscFunctionBeginUser;
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = write(res, ctx);
  PetscCall(PetscPopErrorHandler());
  if (ierr) PetscCall(KergsFileWriteFailed(res->path, res->tmppath, what));
  PetscFunctionReturn(0);
}

static PetscErrorCode WriteRows(KergsResults res, void *ctx)
{
  (void)ctx;
  return AppendRows(res);
}

PetscErrorCode KergsResultsFlush(KergsResults res)
{
  PetscReal bytes = KERGS_RESULTS_OVERHEAD;

  PetscFunctionBeginUser;
  if (!res->enabled || !res->viewer) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  /* a new chunk per statistic at most, and the rows */
  bytes += (PetscReal)res->nstats * (8.0 * KERGS_RESULTS_CHUNK + 8.0 * (PetscReal)(res->nrows - res->nflushed));
  PetscCall(KergsFileCheckSpace(res->comm, res->path, res->tmppath, "the statistics", bytes));
  PetscCall(Guarded(res, WriteRows, NULL, "the statistics"));
  res->nflushed = res->nrows;
  DropFlushedRows(res);
  PetscCall(ResultsRefreshXdmf(res, PETSC_FALSE, PETSC_FALSE)); /* after the flush: it references what the file holds */
  PetscCall(PetscTime(&res->last_flush));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsEndStep(KergsResults res)
{
  PetscFunctionBeginUser;
  PetscCall(ResultsReserveRow(res, res->nrows + 1));
  res->nrows++;
  if (res->enabled && res->viewer) {
    int due = res->flush_every > 0 && res->nrows - res->nflushed >= res->flush_every;
    if (!due && res->flush_seconds > 0) { /* rank 0's clock decides for every rank */
      PetscMPIInt    rank;
      PetscLogDouble now;
      PetscCallMPI(MPI_Comm_rank(res->comm, &rank));
      PetscCall(PetscTime(&now));
      due = rank == 0 && now - res->last_flush >= res->flush_seconds;
      PetscCallMPI(MPI_Bcast(&due, 1, MPI_INT, 0, res->comm));
    }
    if (due) PetscCall(KergsResultsFlush(res));
  }
  PetscFunctionReturn(0);
}

/* Whether the current (not yet ended) row holds any value. */
static PetscBool ResultsPendingRow(KergsResults res)
{
  for (PetscInt j = 0; j < res->nstats; j++)
    if (res->nrows - res->row0 < res->nalloc && !PetscIsNanReal(res->statvalues[j][res->nrows - res->row0])) return PETSC_TRUE;
  return PETSC_FALSE;
}

static PetscErrorCode WriteEnd(KergsResults res, void *ctx)
{
  (void)ctx;
  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "complete", PETSC_INT, &(PetscInt){1}));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, "/", "end", PETSC_STRING, res->end[0] ? res->end : "done"));
  PetscCall(PetscViewerDestroy(&res->viewer)); /* H5Fclose writes what is left */
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsClose(KergsResults res)
{
  PetscFunctionBeginUser;
  if (!res->enabled || !res->viewer) PetscFunctionReturn(0);
  if (res->nalloc && ResultsPendingRow(res)) PetscCall(KergsResultsEndStep(res));
  PetscCall(KergsResultsFlush(res));
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(Guarded(res, WriteEnd, NULL, "the end of the file"));
  PetscCall(KergsFileCommit(res->comm, res->tmppath, res->path));
  PetscCall(ResultsRefreshXdmf(res, PETSC_TRUE, PETSC_TRUE)); /* now the final name */
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsDiscard(KergsResults res)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  if (!res->enabled || !res->viewer || res->source[0]) PetscFunctionReturn(0); /* a continued file holds an earlier run's rows */
  PetscCall(PetscViewerDestroy(&res->viewer));
  PetscCallMPI(MPI_Barrier(res->comm)); /* closed on every rank */
  PetscCallMPI(MPI_Comm_rank(res->comm, &rank));
  if (rank == 0) {
    (void)remove(res->tmppath);
    if (res->xdmf && res->xdmf_written) (void)remove(res->xdmfpath);
  }
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsDestroy(KergsResults *res)
{
  PetscFunctionBeginUser;
  if (!*res) PetscFunctionReturn(0);
  /* Not closed: the temporary file stays as it is (as flushed last), never renamed to the final name. */
  PetscCall(PetscViewerDestroy(&(*res)->viewer));
  for (PetscInt j = 0; j < (*res)->nstats; j++) PetscCall(PetscFree((*res)->statvalues[j]));
  PetscCall(PetscFree((*res)->snaps));
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
  PetscReal    *nrm, *gap, *r, *seg;

  PetscFunctionBeginUser;
  if (contacts) PetscCall(KergsContactsGetLocal(contacts, &m, &cts));
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(KergsSceneGetModel(scene, &scfrictional, NULL));
  PetscCall(PetscMalloc6(m, &a, m, &b, m, &kind, m * KERGS_DIM, &nrm, m, &gap, m * KERGS_MAXCOMP, &r));
  PetscCall(PetscMalloc1(m * KERGS_WALL_COLUMNS, &seg));
  for (PetscInt k = 0; k < m; k++) {
    const KergsContact *c = &cts[k];
    a[k]                  = D.gidx[c->a];
    /* a contact that holds only its key (b < 0: migrated or restored on another number of ranks) until the next detection */
    b[k] = c->kind == KERGS_CONTACT_DISK_DISK ? (c->b >= 0 ? D.gidx[c->b] : -1) : c->b;
    /* the force-chain segment: centre of a, then centre of b (disk) or the contact point x_a - R_a n (wall) */
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      seg[k * KERGS_WALL_COLUMNS + d] = D.x[c->a * KERGS_DIM + d];
      if (c->kind == KERGS_CONTACT_DISK_DISK)
        seg[k * KERGS_WALL_COLUMNS + KERGS_DIM + d] = c->b >= 0 ? D.x[c->b * KERGS_DIM + d] : D.x[c->a * KERGS_DIM + d];
      else
        seg[k * KERGS_WALL_COLUMNS + KERGS_DIM + d] = D.x[c->a * KERGS_DIM + d] - D.radius[c->a] * c->n[d];
    }
    kind[k] = c->kind == KERGS_CONTACT_DISK_WALL ? 1 : 0;
    gap[k]  = c->gap;
    for (PetscInt d = 0; d < KERGS_DIM; d++) nrm[k * KERGS_DIM + d] = c->n[d];
    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) r[k * KERGS_MAXCOMP + j] = (j == 0 || scfrictional) ? c->r[j] : 0.0;
  }
  PetscCall(KergsViewIntegers(viewer, comm, "a", m, a));
  PetscCall(KergsViewIntegers(viewer, comm, "b", m, b));
  PetscCall(KergsViewIntegers(viewer, comm, "kind", m, kind));
  PetscCall(KergsViewBlocks(viewer, comm, "n", m, KERGS_DIM, nrm));
  PetscCall(KergsViewBlocks(viewer, comm, "gap", m, 1, gap));
  PetscCall(KergsViewBlocks(viewer, comm, "r", m, KERGS_MAXCOMP, r));
  PetscCall(KergsViewBlocks(viewer, comm, "segment", m, KERGS_WALL_COLUMNS, seg));
  PetscCall(PetscFree6(a, b, kind, nrm, gap, r));
  PetscCall(PetscFree(seg));
  PetscFunctionReturn(0);
}

/* What a snapshot writes, for the guarded write. */
typedef struct {
  KergsScene    scene;
  KergsContacts contacts;
  PetscInt      step, nwalls, ncontacts;
  PetscReal     time;
} SnapshotWork;

static PetscErrorCode WriteSnapshot(KergsResults res, void *ctx)
{
  SnapshotWork *w = (SnapshotWork *)ctx;
  KergsDisks    D;
  char          group[64];

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(w->scene, &D));
  PetscCall(PetscSNPrintf(group, sizeof(group), "/snapshots/%06" PetscInt_FMT, res->nsnapshots));
  PetscCall(PetscViewerHDF5PushGroup(res->viewer, group));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "step", PETSC_INT, &w->step));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "time", PETSC_REAL, &w->time));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "ndisks", PETSC_INT, &D.ndisks));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "nwalls", PETSC_INT, &w->nwalls));
  PetscCall(PetscViewerHDF5WriteAttribute(res->viewer, NULL, "ncontacts", PETSC_INT, &w->ncontacts));
  PetscCall(SnapshotDisks(res->viewer, w->scene));
  PetscCall(SnapshotWalls(res->viewer, w->scene));
  PetscCall(SnapshotContacts(res->viewer, w->scene, w->contacts));
  PetscCall(PetscViewerHDF5PopGroup(res->viewer));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsResultsSnapshot(KergsResults res, KergsScene scene, KergsContacts contacts)
{
  KergsDisks   D;
  SnapshotWork w      = {scene, contacts, 0, 0, 0, 0};
  PetscInt     nlocal = 0;
  char         what[64];
  PetscReal    bytes;

  PetscFunctionBeginUser;
  if (contacts) PetscCall(KergsContactsGetLocal(contacts, &nlocal, NULL));
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetStep(scene, &w.step, &w.time, NULL));
  PetscCall(KergsSceneGetWalls(scene, &w.nwalls, NULL));
  if (!res->enabled) PetscFunctionReturn(0);
  PetscCheck(res->viewer, res->comm, PETSC_ERR_ORDER, "Results file %s is not open: call KergsResultsOpen() before KergsResultsSnapshot()",
             res->path[0] ? res->path : "(unnamed)");
  if (w.step == res->last_snapshot_step) PetscFunctionReturn(0);
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(MPIU_Allreduce(&nlocal, &w.ncontacts, 1, MPIU_INT, MPI_SUM, res->comm));
  /* per disk id, x, v, rot, omega, radius, material; per wall 5 values; per contact a, b, kind, n, gap, r, segment */
  bytes = 8.0 * ((PetscReal)D.ndisks * (5 + 2 * KERGS_DIM) + (PetscReal)w.nwalls * (KERGS_WALL_COLUMNS + 1) +
                 (PetscReal)w.ncontacts * (4 + KERGS_DIM + KERGS_MAXCOMP + KERGS_WALL_COLUMNS)) +
          KERGS_RESULTS_OVERHEAD;
  PetscCall(PetscSNPrintf(what, sizeof(what), "the snapshot of step %" PetscInt_FMT, w.step));
  PetscCall(KergsFileCheckSpace(res->comm, res->path, res->tmppath, what, bytes));
  PetscCall(Guarded(res, WriteSnapshot, &w, what));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscCall(ResultsKeepSnapshot(res, res->nsnapshots, &(KergsXdmfSnapshot){w.step, w.time, D.ndisks, w.nwalls, w.ncontacts}));
  res->nsnapshots++;
  res->last_snapshot_step = w.step;
  PetscCall(KergsResultsFlush(res)); /* a completed snapshot survives a killed run */
  PetscFunctionReturn(0);
}
