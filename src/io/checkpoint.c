/* kergs checkpoint: write and restore the whole state of a run (include/kergs/checkpoint.h; layout in docs/results.md,
   "Checkpoint file"). Written through PetscViewerHDF5 like the results file: datasets in global order, each rank
   writing its own part, integers stored as reals (exact up to 2^53); the per-rank counts let a restart on the same
   number of ranks give every rank back exactly its disks, ghosts and contacts. */
#include <kergs/checkpoint.h>
#include <kergs/private/h5probe.h>
#include <petscviewerhdf5.h>
#include <petsclayouthdf5.h> /* PetscViewerHDF5ReadSizes */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define KERGS_CHECKPOINT_FORMAT "kergs checkpoint 1"

/* What one rank writes or reads of the per-rank table /ranks. */
enum { RANK_DSTART, RANK_NOWNED, RANK_NCONTACTS, RANK_NGHOSTS, RANK_COMPUTE_SECONDS, RANK_WORK_SCALE, RANK_FIELDS };
static const char *const RankFields[RANK_FIELDS] = {"dstart", "nowned", "ncontacts", "nghosts", "compute_seconds", "work_scale"};

/* ------------------------------------------------------------------------------------------------ */
/* Writing                                                                                          */

typedef struct {
  const char          *path;
  KergsScene           scene;
  KergsContacts        contacts;
  KergsPartition       partition;
  KergsResults         results;
  const KergsRunState *run;
} WriteWork;

static PetscErrorCode WriteInt(PetscViewer v, const char group[], const char name[], PetscInt value)
{
  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5WriteAttribute(v, group, name, PETSC_INT, &value));
  PetscFunctionReturn(0);
}

static PetscErrorCode WriteReal(PetscViewer v, const char group[], const char name[], PetscReal value)
{
  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5WriteAttribute(v, group, name, PETSC_REAL, &value));
  PetscFunctionReturn(0);
}

static PetscErrorCode WriteRoot(PetscViewer v, MPI_Comm comm, KergsScene sc)
{
  KergsProvenance prov;
  PetscInt        step;
  PetscReal       time;
  const char     *name;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetStep(sc, &step, &time, NULL));
  PetscCall(KergsSceneGetName(sc, &name));
  PetscCall(KergsProvenanceGet(comm, &prov));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "kergs_format", PETSC_STRING, KERGS_CHECKPOINT_FORMAT));
  PetscCall(WriteInt(v, "/", "dim", KERGS_DIM));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "kergs_version", PETSC_STRING, prov.version));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "options", PETSC_STRING, prov.options));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "date", PETSC_STRING, prov.date));
  PetscCall(WriteInt(v, "/", "ranks", prov.ranks));
  PetscCall(PetscViewerHDF5WriteAttribute(v, "/", "scene_name", PETSC_STRING, name));
  PetscCall(WriteInt(v, "/", "step", step));
  PetscCall(WriteReal(v, "/", "time", time));
  PetscCall(KergsProvenanceDestroy(&prov));
  PetscFunctionReturn(0);
}

/* /disks: every per-disk field of the owned disks, in global-index order; xref: the positions the ghost layer was
   built from (the positions themselves when there is no layer). */
static PetscErrorCode WriteDisks(PetscViewer v, MPI_Comm comm, KergsScene sc)
{
  KergsDisks       D;
  const PetscReal *xref;
  PetscBool        layer;
  PetscInt         rebuilds;
  PetscReal        ghost_margin;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetGhostState(sc, &layer, &xref, &ghost_margin, &rebuilds));
  PetscCall(PetscViewerHDF5PushGroup(v, "/disks"));
  PetscCall(KergsViewIntegers(v, comm, "id", D.nowned, D.id));
  PetscCall(KergsViewIntegers(v, comm, "material", D.nowned, D.material));
  PetscCall(KergsViewBlocks(v, comm, "x", D.nowned, KERGS_DIM, D.x));
  PetscCall(KergsViewBlocks(v, comm, "v", D.nowned, KERGS_DIM, D.v));
  PetscCall(KergsViewBlocks(v, comm, "rot", D.nowned, KERGS_NROT, D.rot));
  PetscCall(KergsViewBlocks(v, comm, "omega", D.nowned, KERGS_NROT, D.omega));
  PetscCall(KergsViewBlocks(v, comm, "radius", D.nowned, 1, D.radius));
  PetscCall(KergsViewBlocks(v, comm, "xref", D.nowned, KERGS_DIM, layer ? xref : D.x));
  PetscCall(WriteInt(v, NULL, "ndisks", D.ndisks));
  PetscCall(WriteInt(v, NULL, "ghost_layer", layer ? 1 : 0));
  PetscCall(WriteInt(v, NULL, "ghost_rebuilds", rebuilds));
  PetscCall(WriteReal(v, NULL, "ghost_margin", ghost_margin));
  /* the ghosts: global indices of the disks of other ranks held here, in local order */
  {
    PetscInt *gidx;
    PetscCall(PetscMalloc1(D.nlocal - D.nowned + 1, &gidx));
    for (PetscInt k = 0; k < D.nlocal - D.nowned; k++) gidx[k] = D.gidx[D.nowned + k];
    PetscCall(KergsViewIntegers(v, comm, "ghosts", D.nlocal - D.nowned, gidx));
    PetscCall(PetscFree(gidx));
  }
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscFunctionReturn(0);
}

/* /walls (rank 0 writes, the walls are replicated): endpoints a, b, velocity v, displacement disp; names as an
   attribute, to check them against the restarted run's options. */
static PetscErrorCode WriteWalls(PetscViewer v, MPI_Comm comm, KergsScene sc)
{
  const KergsWall *walls;
  PetscInt         nwalls, n;
  PetscMPIInt      rank;
  PetscReal       *f[4];
  const char      *names[4] = {"a", "b", "v", "disp"};
  char            *joined;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetWalls(sc, &nwalls, &walls));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  n = rank == 0 ? nwalls : 0;
  for (int k = 0; k < 4; k++) PetscCall(PetscMalloc1(KERGS_DIM * n + 1, &f[k]));
  for (PetscInt w = 0; w < n; w++)
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      f[0][KERGS_DIM * w + d] = walls[w].a[d];
      f[1][KERGS_DIM * w + d] = walls[w].b[d];
      f[2][KERGS_DIM * w + d] = walls[w].v[d];
      f[3][KERGS_DIM * w + d] = walls[w].disp[d];
    }
  PetscCall(PetscViewerHDF5PushGroup(v, "/walls"));
  for (int k = 0; k < 4; k++) PetscCall(KergsViewBlocks(v, comm, names[k], n, KERGS_DIM, f[k]));
  PetscCall(KergsSceneGetWallNames(sc, &joined));
  PetscCall(WriteInt(v, NULL, "nwalls", nwalls));
  PetscCall(PetscViewerHDF5WriteAttribute(v, NULL, "names", PETSC_STRING, joined));
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscCall(PetscFree(joined));
  for (int k = 0; k < 4; k++) PetscCall(PetscFree(f[k]));
  PetscFunctionReturn(0);
}

/* /contacts, in global contact order: a by grain id, kind, id of b (the key of the warm start), the geometry the
   partition's measures read before the next detection, the impulse r, and whether the pair persisted. */
static PetscErrorCode WriteContacts(PetscViewer v, MPI_Comm comm, KergsScene sc, KergsContacts ct)
{
  KergsDisks    D;
  KergsContact *c;
  PetscInt      m, *ida, *kind, *idb, *persistent;
  PetscReal    *n, *ra, *rb, *gap, *mu, *r;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsContactsGetLocal(ct, &m, &c));
  PetscCall(PetscMalloc4(m + 1, &ida, m + 1, &kind, m + 1, &idb, m + 1, &persistent));
  PetscCall(PetscMalloc6(KERGS_DIM * m + 1, &n, m + 1, &ra, m + 1, &rb, m + 1, &gap, m + 1, &mu, KERGS_MAXCOMP * m + 1, &r));
  for (PetscInt k = 0; k < m; k++) {
    ida[k]        = D.id[c[k].a];
    kind[k]       = c[k].kind == KERGS_CONTACT_DISK_WALL ? 1 : 0;
    idb[k]        = c[k].idb;
    persistent[k] = c[k].persistent ? 1 : 0;
    ra[k]         = c[k].ra;
    rb[k]         = c[k].rb;
    gap[k]        = c[k].gap;
    mu[k]         = c[k].mu;
    for (PetscInt d = 0; d < KERGS_DIM; d++) n[KERGS_DIM * k + d] = c[k].n[d];
    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) r[KERGS_MAXCOMP * k + j] = c[k].r[j];
  }
  PetscCall(PetscViewerHDF5PushGroup(v, "/contacts"));
  PetscCall(KergsViewIntegers(v, comm, "a_id", m, ida));
  PetscCall(KergsViewIntegers(v, comm, "kind", m, kind));
  PetscCall(KergsViewIntegers(v, comm, "b_id", m, idb));
  PetscCall(KergsViewIntegers(v, comm, "persistent", m, persistent));
  PetscCall(KergsViewBlocks(v, comm, "n", m, KERGS_DIM, n));
  PetscCall(KergsViewBlocks(v, comm, "ra", m, 1, ra));
  PetscCall(KergsViewBlocks(v, comm, "rb", m, 1, rb));
  PetscCall(KergsViewBlocks(v, comm, "gap", m, 1, gap));
  PetscCall(KergsViewBlocks(v, comm, "mu", m, 1, mu));
  PetscCall(KergsViewBlocks(v, comm, "r", m, KERGS_MAXCOMP, r));
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscCall(PetscFree4(ida, kind, idb, persistent));
  PetscCall(PetscFree6(n, ra, rb, gap, mu, r));
  PetscFunctionReturn(0);
}

/* /ranks: one entry per rank (disk range, counts, the partition's measured work), and /state: the scalars of the
   partition, the results writer and the time loop. */
static PetscErrorCode WriteState(PetscViewer v, MPI_Comm comm, const WriteWork *w)
{
  KergsDisks          D;
  KergsPartitionState ps;
  KergsResultsState   rs;
  PetscReal           mine[RANK_FIELDS], alert, alert_floor;
  PetscInt            m;
  const char         *path;
  PetscBool           enabled;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(w->scene, &D));
  PetscCall(KergsContactsGetLocal(w->contacts, &m, NULL));
  PetscCall(KergsPartitionGetState(w->partition, &ps));
  PetscCall(KergsResultsGetState(w->results, &rs));
  PetscCall(KergsResultsGetPath(w->results, &path, &enabled));
  PetscCall(KergsSceneGetContactRule(w->scene, &alert, NULL));
  PetscCall(KergsSceneGetAlertFloor(w->scene, NULL, &alert_floor));
  mine[RANK_DSTART]          = (PetscReal)D.dstart;
  mine[RANK_NOWNED]          = (PetscReal)D.nowned;
  mine[RANK_NCONTACTS]       = (PetscReal)m;
  mine[RANK_NGHOSTS]         = (PetscReal)(D.nlocal - D.nowned);
  mine[RANK_COMPUTE_SECONDS] = ps.compute_seconds;
  mine[RANK_WORK_SCALE]      = ps.work_scale;
  PetscCall(PetscViewerHDF5PushGroup(v, "/ranks"));
  for (int k = 0; k < RANK_FIELDS; k++) PetscCall(KergsViewBlocks(v, comm, RankFields[k], 1, 1, &mine[k]));
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscCall(PetscViewerHDF5PushGroup(v, "/state"));
  PetscCall(WriteReal(v, NULL, "alert", alert));
  PetscCall(WriteReal(v, NULL, "alert_floor", alert_floor));
  PetscCall(WriteInt(v, NULL, "partition_initialized", ps.initialized ? 1 : 0));
  PetscCall(WriteInt(v, NULL, "partition_provisional", ps.provisional ? 1 : 0));
  PetscCall(WriteInt(v, NULL, "partition_edgecut_base", ps.edgecut_base));
  PetscCall(WriteInt(v, NULL, "partition_repartitions", ps.nrepartitions));
  PetscCall(WriteInt(v, NULL, "partition_moved", ps.nmoved));
  PetscCall(WriteInt(v, NULL, "partition_last_method", ps.last_method));
  PetscCall(WriteReal(v, NULL, "partition_imbalance_base", ps.imbalance_base));
  PetscCall(WriteInt(v, NULL, "results_enabled", enabled ? 1 : 0));
  PetscCall(PetscViewerHDF5WriteAttribute(v, NULL, "results_path", PETSC_STRING, path));
  PetscCall(WriteInt(v, NULL, "results_rows", rs.nrows));
  PetscCall(WriteInt(v, NULL, "results_snapshots", rs.nsnapshots));
  PetscCall(WriteInt(v, NULL, "results_last_snapshot_step", rs.last_snapshot_step));
  PetscCall(WriteInt(v, NULL, "nonconverged", w->run->nonconverged));
  PetscCall(WriteReal(v, NULL, "max_violation", w->run->max_violation));
  PetscCall(WriteInt(v, NULL, "moved", w->run->moved ? 1 : 0));
  PetscCall(WriteInt(v, NULL, "inertial_armed", w->run->armed ? 1 : 0));
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscFunctionReturn(0);
}

static PetscErrorCode WriteAll(MPI_Comm comm, const char tmp[], const WriteWork *w)
{
  PetscViewer v;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5Open(comm, tmp, FILE_MODE_WRITE, &v));
  PetscCall(PetscViewerHDF5SetBaseDimension2(v, PETSC_FALSE));
  PetscCall(PetscViewerHDF5SetSPOutput(v, PETSC_FALSE));
  PetscCall(WriteRoot(v, comm, w->scene));
  PetscCall(WriteDisks(v, comm, w->scene));
  PetscCall(WriteWalls(v, comm, w->scene));
  PetscCall(WriteContacts(v, comm, w->scene, w->contacts));
  PetscCall(WriteState(v, comm, w));
  PetscCall(PetscViewerDestroy(&v));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsCheckpointWrite(const char path[], KergsScene sc, KergsContacts ct, KergsPartition p, KergsResults res,
                                    const KergsRunState *run)
{
  WriteWork      w = {path, sc, ct, p, res, run};
  MPI_Comm       comm;
  KergsDisks     D;
  PetscInt       m, mall, step;
  char           tmp[PETSC_MAX_PATH_LEN + 8], what[64];
  PetscReal      bytes;
  PetscErrorCode ierr;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetComm(sc, &comm));
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetStep(sc, &step, NULL, NULL));
  PetscCall(KergsContactsGetLocal(ct, &m, NULL));
  PetscCheck(path && path[0], comm, PETSC_ERR_ARG_WRONG, "Checkpoint file name is empty (-checkpoint_path)");
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(MPIU_Allreduce(&m, &mall, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp", path));
  PetscCall(PetscSNPrintf(what, sizeof(what), "the checkpoint of step %" PetscInt_FMT, step));
  PetscCall(KergsFileMakeParentDir(comm, path));
  /* per disk 10 + 2 KERGS_DIM values and at most one ghost each, per contact 9 + KERGS_DIM + KERGS_MAXCOMP, metadata */
  bytes = 8.0 * ((PetscReal)D.ndisks * (11 + 2 * KERGS_DIM) + (PetscReal)mall * (7 + KERGS_DIM + KERGS_MAXCOMP)) + 131072.0;
  PetscCall(KergsFileCheckSpace(comm, path, tmp, what, bytes));
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = WriteAll(comm, tmp, &w);
  PetscCall(PetscPopErrorHandler());
  if (ierr) PetscCall(KergsFileWriteFailed(path, tmp, what)); /* the previous checkpoint under path is untouched */
  PetscCall(KergsFileCommit(comm, tmp, path));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Reading                                                                                          */

/* PETSc's viewer only ever opens a readable HDF5 file holding a kergs checkpoint. */
static PetscErrorCode CheckFile(MPI_Comm comm, const char path[])
{
  PetscFunctionBeginUser;
  PetscCall(KergsH5CheckFile(comm, path, "Checkpoint file (-restart)", KERGS_CHECKPOINT_FORMAT, "kergs checkpoint"));
  PetscFunctionReturn(0);
}

/* A root or group attribute the checkpoint must hold, of the given type; its absence names the file and attribute. */
static PetscErrorCode ReadAttribute(PetscViewer v, const char path[], const char group[], const char name[], PetscDataType type,
                                    void *value)
{
  PetscBool has;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5HasAttribute(v, group, name, &has));
  PetscCheck(has, PetscObjectComm((PetscObject)v), PETSC_ERR_FILE_UNEXPECTED, "Checkpoint file %s has no attribute %s on %s", path, name,
             group);
  PetscCall(PetscViewerHDF5ReadAttribute(v, group, name, type, NULL, value));
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadInt(PetscViewer v, const char path[], const char group[], const char name[], PetscInt *value)
{
  PetscFunctionBeginUser;
  PetscCall(ReadAttribute(v, path, group, name, PETSC_INT, value));
  PetscFunctionReturn(0);
}

static PetscErrorCode ReadReal(PetscViewer v, const char path[], const char group[], const char name[], PetscReal *value)
{
  PetscFunctionBeginUser;
  PetscCall(ReadAttribute(v, path, group, name, PETSC_REAL, value));
  PetscCheck(!PetscIsInfOrNanReal(*value), PetscObjectComm((PetscObject)v), PETSC_ERR_FILE_UNEXPECTED,
             "Checkpoint file %s: attribute %s on %s is %g, not a finite number", path, name, group, (double)*value);
  PetscFunctionReturn(0);
}

/* A count the checkpoint holds (rows, snapshots, steps not converged): refused when negative, which no run writes. */
static PetscErrorCode ReadCount(PetscViewer v, const char path[], const char group[], const char name[], PetscInt *value)
{
  PetscFunctionBeginUser;
  PetscCall(ReadInt(v, path, group, name, value));
  PetscCheck(*value >= 0, PetscObjectComm((PetscObject)v), PETSC_ERR_FILE_UNEXPECTED,
             "Checkpoint file %s: attribute %s on %s is %" PetscInt_FMT ", not a count", path, name, group, *value);
  PetscFunctionReturn(0);
}

/* What the file says of the run as a whole. */
typedef struct {
  PetscInt   ranks, step, ndisks, ncontacts, nwalls, layer, rebuilds;
  PetscReal  time, alert, alert_floor, ghost_margin;
  PetscReal *rankinfo[RANK_FIELDS]; /* per saved rank */
} Header;

static PetscErrorCode ReadHeader(PetscViewer v, MPI_Comm comm, const char path[], Header *h)
{
  PetscInt dim;

  PetscFunctionBeginUser;
  PetscCall(ReadInt(v, path, "/", "dim", &dim));
  PetscCheck(dim == KERGS_DIM, comm, PETSC_ERR_FILE_UNEXPECTED,
             "Checkpoint file %s is of dimension %" PetscInt_FMT ", kergs computes in %d", path, dim, KERGS_DIM);
  PetscCall(ReadInt(v, path, "/", "ranks", &h->ranks));
  PetscCall(ReadInt(v, path, "/", "step", &h->step));
  PetscCall(ReadReal(v, path, "/", "time", &h->time));
  PetscCall(ReadInt(v, path, "/disks", "ndisks", &h->ndisks));
  PetscCall(ReadInt(v, path, "/disks", "ghost_layer", &h->layer));
  PetscCall(ReadInt(v, path, "/disks", "ghost_rebuilds", &h->rebuilds));
  PetscCall(ReadInt(v, path, "/walls", "nwalls", &h->nwalls));
  PetscCall(ReadReal(v, path, "/state", "alert", &h->alert));
  {
    PetscBool has; /* written before the alert followed the speed: it was fixed, and the layer's margin alert + skin */
    PetscCall(PetscViewerHDF5HasAttribute(v, "/state", "alert_floor", &has));
    if (has)
      PetscCall(ReadReal(v, path, "/state", "alert_floor", &h->alert_floor));
    else
      h->alert_floor = h->alert;
    PetscCall(PetscViewerHDF5HasAttribute(v, "/disks", "ghost_margin", &has));
    if (has)
      PetscCall(ReadReal(v, path, "/disks", "ghost_margin", &h->ghost_margin));
    else
      h->ghost_margin = -1.0;
  }
  PetscCheck(h->ranks >= 1 && h->step >= 0 && h->ndisks >= 0 && h->ndisks <= KERGS_MAX_DISKS && h->nwalls >= 0, comm,
             PETSC_ERR_FILE_UNEXPECTED,
             "Checkpoint file %s: ranks %" PetscInt_FMT ", step %" PetscInt_FMT ", ndisks %" PetscInt_FMT ", nwalls %" PetscInt_FMT
             " are not those of a run",
             path, h->ranks, h->step, h->ndisks, h->nwalls);
  PetscCall(PetscViewerHDF5PushGroup(v, "/ranks"));
  for (int k = 0; k < RANK_FIELDS; k++) PetscCall(KergsLoadAllBlocks(v, comm, path, "/ranks", RankFields[k], h->ranks, 1, &h->rankinfo[k]));
  PetscCall(PetscViewerHDF5PopGroup(v));
  h->ncontacts = 0;
  for (PetscInt q = 0; q < h->ranks; q++) h->ncontacts += (PetscInt)h->rankinfo[RANK_NCONTACTS][q];
  PetscFunctionReturn(0);
}

/* The disks: this rank's range of the checkpoint (same ranks) or an even split; then the clock and the alert. */
static PetscErrorCode RestoreDisks(PetscViewer v, MPI_Comm comm, const char path[], const Header *h, PetscBool same, KergsScene sc,
                                   PetscReal **xref)
{
  PetscMPIInt rank;
  PetscInt    n, n2;
  PetscReal  *id, *mat, *x, *vel, *rot, *omega, *radius;
  PetscInt   *iid, *imat;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  n = same ? (PetscInt)h->rankinfo[RANK_NOWNED][rank] : PETSC_DECIDE;
  PetscCall(PetscViewerHDF5PushGroup(v, "/disks"));
  PetscCall(KergsLoadBlocks(v, comm, path, "/disks", "id", h->ndisks, 1, &n, &id));
  n2 = n;
  PetscCall(KergsLoadBlocks(v, comm, path, "/disks", "material", h->ndisks, 1, &n2, &mat));
  PetscCall(KergsLoadBlocks(v, comm, path, "/disks", "x", h->ndisks, KERGS_DIM, &n2, &x));
  PetscCall(KergsLoadBlocks(v, comm, path, "/disks", "v", h->ndisks, KERGS_DIM, &n2, &vel));
  PetscCall(KergsLoadBlocks(v, comm, path, "/disks", "rot", h->ndisks, KERGS_NROT, &n2, &rot));
  PetscCall(KergsLoadBlocks(v, comm, path, "/disks", "omega", h->ndisks, KERGS_NROT, &n2, &omega));
  PetscCall(KergsLoadBlocks(v, comm, path, "/disks", "radius", h->ndisks, 1, &n2, &radius));
  PetscCall(KergsLoadBlocks(v, comm, path, "/disks", "xref", h->ndisks, KERGS_DIM, &n2, xref));
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscCall(PetscMalloc2(n + 1, &iid, n + 1, &imat));
  for (PetscInt i = 0; i < n; i++) {
    iid[i]  = (PetscInt)id[i];
    imat[i] = (PetscInt)mat[i];
  }
  PetscCall(KergsSceneRestoreDisks(sc, h->ndisks, n, iid, imat, x, rot, vel, omega, radius));
  PetscCall(KergsSceneRestoreState(sc, h->step, h->time, h->alert, h->alert_floor));
  PetscCall(PetscFree2(iid, imat));
  PetscCall(PetscFree(id));
  PetscCall(PetscFree(mat));
  PetscCall(PetscFree(x));
  PetscCall(PetscFree(vel));
  PetscCall(PetscFree(rot));
  PetscCall(PetscFree(omega));
  PetscCall(PetscFree(radius));
  PetscFunctionReturn(0);
}

/* The walls of the options (by name, in order) take the checkpoint's positions, velocities and displacements. */
static PetscErrorCode RestoreWalls(PetscViewer v, MPI_Comm comm, const char path[], const Header *h, KergsScene sc)
{
  const KergsWall *walls;
  PetscInt         nwalls;
  char            *names, *mine;
  PetscReal       *f[4];
  const char      *fields[4] = {"a", "b", "v", "disp"};
  PetscBool        same;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetWalls(sc, &nwalls, &walls));
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/walls", "names", PETSC_STRING, NULL, &names));
  PetscCall(KergsSceneGetWallNames(sc, &mine));
  PetscCall(PetscStrcmp(names, mine, &same));
  PetscCheck(same && nwalls == h->nwalls, comm, PETSC_ERR_FILE_UNEXPECTED,
             "Checkpoint file %s holds the walls %s; the options of this run give %s: a restart keeps the walls of its run", path,
             names[0] ? names : "(none)", mine[0] ? mine : "(none)");
  PetscCall(PetscFree(names));
  PetscCall(PetscFree(mine));
  PetscCall(PetscViewerHDF5PushGroup(v, "/walls"));
  for (int k = 0; k < 4; k++) PetscCall(KergsLoadAllBlocks(v, comm, path, "/walls", fields[k], nwalls, KERGS_DIM, &f[k]));
  PetscCall(PetscViewerHDF5PopGroup(v));
  for (PetscInt w = 0; w < nwalls; w++)
    PetscCall(KergsSceneRestoreWall(sc, w, &f[0][KERGS_DIM * w], &f[1][KERGS_DIM * w], &f[2][KERGS_DIM * w], &f[3][KERGS_DIM * w]));
  for (int k = 0; k < 4; k++) PetscCall(PetscFree(f[k]));
  PetscFunctionReturn(0);
}

/* The contact records of the file (this rank's part: nlocal, or all: nlocal PETSC_DETERMINE), by field. */
typedef struct {
  PetscInt   n;
  PetscReal *ida, *kind, *idb, *persistent, *nrm, *ra, *rb, *gap, *mu, *r;
} ContactRecords;

static PetscErrorCode LoadContacts(PetscViewer v, MPI_Comm comm, const char path[], const Header *h, PetscInt nlocal, ContactRecords *cr)
{
  PetscReal **dst[10]   = {&cr->ida, &cr->kind, &cr->idb, &cr->persistent, &cr->nrm, &cr->ra, &cr->rb, &cr->gap, &cr->mu, &cr->r};
  const char *names[10] = {"a_id", "kind", "b_id", "persistent", "n", "ra", "rb", "gap", "mu", "r"};
  PetscInt    bs[10]    = {1, 1, 1, 1, KERGS_DIM, 1, 1, 1, 1, KERGS_MAXCOMP};

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5PushGroup(v, "/contacts"));
  for (int k = 0; k < 10; k++) {
    PetscInt n = nlocal;
    if (nlocal == PETSC_DETERMINE) {
      PetscCall(KergsLoadAllBlocks(v, comm, path, "/contacts", names[k], h->ncontacts, bs[k], dst[k]));
      n = h->ncontacts;
    } else
      PetscCall(KergsLoadBlocks(v, comm, path, "/contacts", names[k], h->ncontacts, bs[k], &n, dst[k]));
    cr->n = n;
  }
  PetscCall(PetscViewerHDF5PopGroup(v));
  PetscFunctionReturn(0);
}

static PetscErrorCode FreeContacts(ContactRecords *cr)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(cr->ida));
  PetscCall(PetscFree(cr->kind));
  PetscCall(PetscFree(cr->idb));
  PetscCall(PetscFree(cr->persistent));
  PetscCall(PetscFree(cr->nrm));
  PetscCall(PetscFree(cr->ra));
  PetscCall(PetscFree(cr->rb));
  PetscCall(PetscFree(cr->gap));
  PetscCall(PetscFree(cr->mu));
  PetscCall(PetscFree(cr->r));
  PetscFunctionReturn(0);
}

/* Contact k of the records as a contact of this rank; whole (b found among the disks held here) or, when `keyonly`,
   only its key and impulse (b = -1: the next detection warm-starts from it). */
static void ContactOf(const ContactRecords *cr, PetscInt k, PetscInt a, PetscInt b, PetscBool keyonly, KergsContact *c)
{
  memset(c, 0, sizeof(*c));
  c->kind = cr->kind[k] != 0 ? KERGS_CONTACT_DISK_WALL : KERGS_CONTACT_DISK_DISK;
  c->a    = a;
  c->b    = keyonly ? -1 : b;
  c->idb  = (PetscInt)cr->idb[k];
  for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) c->r[j] = cr->r[KERGS_MAXCOMP * k + j];
  if (keyonly) return;
  c->n[0]       = cr->nrm[KERGS_DIM * k];
  c->n[1]       = cr->nrm[KERGS_DIM * k + 1];
  c->t[0]       = -c->n[1]; /* t = (-n_y, n_x), as detection sets it */
  c->t[1]       = c->n[0];
  c->ra         = cr->ra[k];
  c->rb         = cr->rb[k];
  c->gap        = cr->gap[k];
  c->mu         = cr->mu[k];
  c->persistent = cr->persistent[k] != 0 ? PETSC_TRUE : PETSC_FALSE;
}

/* Same ranks: the ghost layer, then every contact whole, on the rank that held it. */
static PetscErrorCode RestoreExact(PetscViewer v, MPI_Comm comm, const char path[], const Header *h, const PetscReal *xref, KergsScene sc,
                                   KergsContacts ct)
{
  KergsDisks       D;
  PetscMPIInt      rank;
  PetscInt         ng, nc, *gidx, nwalls;
  PetscReal       *g;
  ContactRecords   cr = {0};
  KergsGrainIndex *table;
  KergsContact    *c;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  ng = (PetscInt)h->rankinfo[RANK_NGHOSTS][rank];
  nc = (PetscInt)h->rankinfo[RANK_NCONTACTS][rank];
  {
    PetscInt total = 0;
    for (PetscInt q = 0; q < h->ranks; q++) total += (PetscInt)h->rankinfo[RANK_NGHOSTS][q];
    PetscCall(PetscViewerHDF5PushGroup(v, "/disks"));
    PetscCall(KergsLoadBlocks(v, comm, path, "/disks", "ghosts", total, 1, &ng, &g));
    PetscCall(PetscViewerHDF5PopGroup(v));
  }
  PetscCall(PetscMalloc1(ng + 1, &gidx));
  for (PetscInt k = 0; k < ng; k++) gidx[k] = (PetscInt)g[k];
  PetscCall(KergsSceneRestoreGhosts(sc, h->layer ? PETSC_TRUE : PETSC_FALSE, ng, gidx, xref, h->ghost_margin, h->rebuilds));
  PetscCall(PetscFree(gidx));
  PetscCall(PetscFree(g));
  PetscCall(LoadContacts(v, comm, path, h, nc, &cr));
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetWalls(sc, &nwalls, NULL));
  PetscCall(KergsSceneGetGrainIndex(sc, D.nlocal, &table));
  PetscCall(PetscMalloc1(nc + 1, &c));
  for (PetscInt k = 0; k < nc; k++) {
    const PetscInt ida = (PetscInt)cr.ida[k], idb = (PetscInt)cr.idb[k], a = KergsGrainIndexFind(table, D.nlocal, ida);
    const PetscInt b = cr.kind[k] != 0 ? idb : KergsGrainIndexFind(table, D.nlocal, idb);
    PetscCheck(a >= 0 && a < D.nowned && b >= 0 && (cr.kind[k] != 0 ? b < nwalls : b < D.nlocal), PETSC_COMM_SELF,
               PETSC_ERR_FILE_UNEXPECTED,
               "Checkpoint file %s: contact of grain %" PetscInt_FMT " with %s %" PetscInt_FMT " is not on rank %d's disks", path, ida,
               cr.kind[k] != 0 ? "wall" : "grain", idb, rank);
    ContactOf(&cr, k, a, b, PETSC_FALSE, &c[k]);
  }
  PetscCall(KergsContactsRestore(ct, nc, c));
  PetscCall(PetscFree(c));
  PetscCall(PetscFree(table));
  PetscCall(FreeContacts(&cr));
  PetscFunctionReturn(0);
}

static int CompareContactKeys(const void *p, const void *q) { return KERGS_COMPARE_KEYS((const KergsContact *)p, (const KergsContact *)q); }

/* Another number of ranks: a new initial partition, then the contacts of the grains owned here as warm start of a
   detection at the restored positions. */
static PetscErrorCode RestoreRepartitioned(PetscViewer v, MPI_Comm comm, const char path[], const Header *h, KergsScene sc,
                                           KergsContacts ct, KergsPartition p)
{
  KergsDisks       D;
  ContactRecords   cr = {0};
  KergsGrainIndex *table;
  KergsContact    *c;
  PetscInt         nc = 0;

  PetscFunctionBeginUser;
  PetscCall(KergsContactsRestore(ct, 0, NULL));
  PetscCall(KergsSceneRestoreGhosts(sc, PETSC_FALSE, 0, NULL, NULL, 0.0, 0));
  PetscCall(KergsPartitionSetState(p, NULL));
  PetscCall(KergsPartitionUpdate(p, sc, ct, NULL)); /* the initial partition of a new run: no contacts yet */
  PetscCall(LoadContacts(v, comm, path, h, PETSC_DETERMINE, &cr));
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetGrainIndex(sc, D.nowned, &table));
  PetscCall(PetscMalloc1(cr.n + 1, &c));
  for (PetscInt k = 0; k < cr.n; k++) {
    const PetscInt a = KergsGrainIndexFind(table, D.nowned, (PetscInt)cr.ida[k]);
    if (a >= 0) ContactOf(&cr, k, a, -1, PETSC_TRUE, &c[nc++]);
  }
  qsort(c, (size_t)nc, sizeof(KergsContact), CompareContactKeys);
  PetscCall(KergsContactsRestore(ct, nc, c));
  PetscCall(KergsContactsDetect(ct, sc)); /* the contacts of the restored positions, impulses carried over */
  PetscCall(PetscFree(c));
  PetscCall(PetscFree(table));
  PetscCall(FreeContacts(&cr));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsCheckpointRead(const char path[], KergsScene sc, KergsContacts ct, KergsPartition p, KergsResults res,
                                   KergsRunState *run)
{
  MPI_Comm          comm;
  PetscViewer       v;
  PetscMPIInt       size, rank;
  Header            h = {0};
  PetscReal        *xref;
  PetscBool         same, enabled, has;
  PetscInt          flag;
  KergsResultsState rs;
  char             *source;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetComm(sc, &comm));
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(CheckFile(comm, path));
  PetscCall(PetscViewerHDF5Open(comm, path, FILE_MODE_READ, &v));
  PetscCall(ReadHeader(v, comm, path, &h));
  same = (PetscBool)(h.ranks == size);
  if (!same) /* measured: confine500 frictionless, 4 + 4 steps, 2 -> 1 ranks: 1.4e-14 m on positions against 8 steps */
    PetscCall(PetscPrintf(comm,
                          "kergs: restart of a checkpoint written on %" PetscInt_FMT
                          " rank(s) on %d: the disks are partitioned anew, so the "
                          "run continues to rounding, not bit for bit (docs/running.md, Restart)\n",
                          h.ranks, (int)size));
  PetscCall(RestoreDisks(v, comm, path, &h, same, sc, &xref));
  PetscCall(RestoreWalls(v, comm, path, &h, sc));
  PetscCall(KergsSceneCheck(sc)); /* the restored state against the options of this run (materials, ...) */
  if (same) {
    KergsPartitionState ps;
    PetscCall(RestoreExact(v, comm, path, &h, xref, sc, ct));
    PetscCall(ReadInt(v, path, "/state", "partition_initialized", &flag));
    ps.initialized = flag ? PETSC_TRUE : PETSC_FALSE;
    PetscCall(ReadInt(v, path, "/state", "partition_provisional", &flag));
    ps.provisional = flag ? PETSC_TRUE : PETSC_FALSE;
    PetscCall(ReadInt(v, path, "/state", "partition_edgecut_base", &ps.edgecut_base));
    PetscCall(ReadInt(v, path, "/state", "partition_repartitions", &ps.nrepartitions));
    PetscCall(ReadInt(v, path, "/state", "partition_moved", &ps.nmoved));
    PetscCall(ReadInt(v, path, "/state", "partition_last_method", &ps.last_method));
    PetscCall(ReadReal(v, path, "/state", "partition_imbalance_base", &ps.imbalance_base));
    ps.compute_seconds = h.rankinfo[RANK_COMPUTE_SECONDS][rank];
    ps.work_scale      = h.rankinfo[RANK_WORK_SCALE][rank];
    PetscCall(KergsPartitionSetState(p, &ps));
  } else
    PetscCall(RestoreRepartitioned(v, comm, path, &h, sc, ct, p));
  PetscCall(ReadCount(v, path, "/state", "nonconverged", &run->nonconverged));
  PetscCall(ReadReal(v, path, "/state", "max_violation", &run->max_violation));
  PetscCall(ReadInt(v, path, "/state", "moved", &flag));
  run->moved = flag ? PETSC_TRUE : PETSC_FALSE;
  PetscCall(PetscViewerHDF5HasAttribute(v, "/state", "inertial_armed", &has)); /* checkpoints before -stop_at_rest_inertial: none */
  flag = 0;
  if (has) PetscCall(ReadInt(v, path, "/state", "inertial_armed", &flag));
  run->armed = flag ? PETSC_TRUE : PETSC_FALSE;
  PetscCall(ReadInt(v, path, "/state", "results_enabled", &flag));
  PetscCall(ReadCount(v, path, "/state", "results_rows", &rs.nrows));
  PetscCall(ReadCount(v, path, "/state", "results_snapshots", &rs.nsnapshots));
  PetscCall(ReadInt(v, path, "/state", "results_last_snapshot_step", &rs.last_snapshot_step));
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/state", "results_path", PETSC_STRING, NULL, &source));
  PetscCall(KergsResultsGetPath(res, NULL, &enabled));
  if (enabled && flag) PetscCall(KergsResultsSetContinue(res, source, &rs, h.step));
  PetscCall(PetscFree(source));
  PetscCall(PetscViewerDestroy(&v));
  PetscCall(PetscFree(xref));
  for (int k = 0; k < RANK_FIELDS; k++) PetscCall(PetscFree(h.rankinfo[k]));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscCall(PetscInfo(NULL, "Restored step %" PetscInt_FMT " of %s (%" PetscInt_FMT " ranks, now %d)\n", h.step, path, h.ranks, size));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Options                                                                                          */

/* Options that make the packing and the container: a restart takes them from the checkpoint (its disks and walls),
   so that a different value on the command line would be ignored while the results record it. */
static PetscBool IsGeometryOption(const char name[])
{
  static const char *prefixes[] = {"-box", "-disks_", "-lattice_", "-random_", "-sample_input", NULL};
  const size_t       n          = strlen(name);

  for (PetscInt i = 0; prefixes[i]; i++)
    if (!strncmp(name, prefixes[i], strlen(prefixes[i]))) return PETSC_TRUE;
  return (PetscBool)(!strncmp(name, "-wall_", 6) && n > 8 && (!strcmp(name + n - 2, "_a") || !strcmp(name + n - 2, "_b")));
}

/* A geometry option given on the restart's command line must be the checkpointed run's. */
static PetscErrorCode CheckGeometryOption(const char name[], const char value[])
{
  char      given[4096];
  PetscBool set;

  PetscFunctionBeginUser;
  if (!IsGeometryOption(name)) PetscFunctionReturn(0);
  PetscCall(PetscOptionsGetString(NULL, NULL, name, given, sizeof(given), &set));
  PetscCheck(!set || !strcmp(given, value), PETSC_COMM_WORLD, PETSC_ERR_USER_INPUT,
             "%s %s differs from the checkpointed run's %s %s: a restart continues that run's packing and walls, which the "
             "checkpoint holds (remove the option, or start a new run)",
             name, given, name, value[0] ? value : "(no value)");
  PetscFunctionReturn(0);
}

/* PETSc's own monitors start in PetscInitialize, from the command line, and PetscFinalize reports them, failing on one
   that never started: a restart of a run made with -log_view, -memory_view or -malloc_view ended with status 1 after
   its checkpoint (measured). -log_view and -memory_view that the checkpoint brings are started as they enter the
   database. -malloc_view needs PETSc's tracing malloc, which only PetscInitialize can install (started later it
   reports 0 bytes): it is left out, with a line saying so. */
static PetscErrorCode InsertCheckpointOption(const char name[], const char value[])
{
  PetscBool is;

  PetscFunctionBeginUser;
  PetscCall(PetscStrncmp(name, "-malloc_view", 12, &is));
  if (is) {
    PetscCall(PetscPrintf(PETSC_COMM_WORLD, "kergs: %s of the checkpointed run is not applied: PETSc takes it from the command line only\n",
                          name));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscOptionsSetValue(NULL, name, value));
  PetscCall(PetscStrcmp(name, "-log_view", &is));
  if (is) PetscCall(PetscLogDefaultBegin());
  PetscCall(PetscStrcmp(name, "-memory_view", &is));
  if (is) PetscCall(PetscMemorySetGetMaximumUsage());
  PetscFunctionReturn(0);
}

/* One option of the checkpointed run: inserted unless the command line gives it (which wins; a geometry option must
   then be the same), -restart never. */
static PetscErrorCode InsertOption(const char name[], const char value[], void *ctx)
{
  PetscBool set, skip;

  PetscFunctionBeginUser;
  (void)ctx;
  PetscCall(PetscStrcmp(name, "-restart", &skip));
  PetscCall(PetscOptionsHasName(NULL, NULL, name, &set));
  if (!skip && set) PetscCall(CheckGeometryOption(name, value));
  if (!skip && !set) PetscCall(InsertCheckpointOption(name, value[0] ? value : NULL));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsCheckpointLoadOptions(MPI_Comm comm, const char path[])
{
  PetscViewer v;
  char       *text;

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  {
    size_t n = strlen(path);
    PetscCheck(n < 4 || strcmp(path + n - 4, ".tmp"), comm, PETSC_ERR_ARG_WRONG,
               "-restart %s is the temporary file of a checkpoint being written (a write that did not finish, or not yet renamed): restart "
               "from %.*s, the last complete checkpoint",
               path, (int)(n - 4), path);
  }
  PetscCall(CheckFile(comm, path));
  PetscCall(PetscViewerHDF5Open(comm, path, FILE_MODE_READ, &v));
  PetscCall(PetscViewerHDF5ReadAttribute(v, "/", "options", PETSC_STRING, NULL, &text));
  PetscCall(PetscViewerDestroy(&v));
  PetscCall(KergsOptionsTextWalk(text, InsertOption, NULL));
  PetscCall(PetscFree(text));
  PetscFunctionReturn(0);
}
