/* io tests (1 and 2 ranks): results file (stats and snapshots round-trip exactly, atomic rename, 1-D stats,
   NaN fill, -output_none), sample write/read round-trip and its errors (truncated, missing, not HDF5, wrong
   layout, a repeated or negative grain id), FCLib export of a hand-built W (read back with libfclib's own reader) and PETSc's HDF5 still
   working after it. The scene's disks are set with KergsSceneSetDisks (distributed: owned slice plus ghosts);
   contacts and operators are built by hand from the headers.
   Option: -dir <directory> for the files written (default test_io_out). */
#define _GNU_SOURCE /* RTLD_DEEPBIND */
#include "testing.h"
#include <petscviewerhdf5.h>
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <fclib.h>
#include "gathered_disks.h"

#ifndef KERGS_FCLIB_LIBRARY
#define KERGS_FCLIB_LIBRARY "libfclib.so.0"
#endif

#define NDISKS 7
#define NWALLS 2

static PetscErrorCode FileExists(MPI_Comm comm, const char path[], PetscBool *exists)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  *exists = PETSC_FALSE;
  if (rank == 0) PetscCall(PetscTestFile(path, 'r', exists));
  PetscCallMPI(MPI_Bcast(exists, 1, MPIU_BOOL, 0, comm));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* A hand-built scene: NDISKS disks on a slightly irregular row, two walls, values with inexact binary
   fractions so that any rounding on the way shows. Contacts: (i, i+1) for every i, and disk 0 on wall 0.
   The disk state is distributed: KergsSceneSetDisks keeps each rank's slice of the full arrays, the fields
   it does not take (rot, omega, id) are set on the owned disks from the Disk* functions of the global index,
   and a ghost layer gives each rank the neighbours its contacts (i, i+1) need as body b. */

static PetscReal DiskX(PetscInt i, PetscInt d, PetscInt step)
{
  return d == 0 ? 2.0 * i + 1.0 / 3.0 + 0.01 * step : 0.1 * PetscSinReal((PetscReal)i) + 1.0 / 7.0;
}
static PetscReal DiskV(PetscInt i, PetscInt d) { return (d ? -0.3 : 0.7) / (i + 3); }
static PetscReal DiskRot(PetscInt i) { return 0.1 * i - 1.0 / 3.0; }
static PetscReal DiskOmega(PetscInt i) { return 1.0 / (i + 11); }
static PetscReal DiskRadius(PetscInt i) { return 1.0 - 0.05 * i; }
static PetscInt  DiskMaterial(PetscInt i) { return i % 2; }
static PetscInt  DiskId(PetscInt i) { return 1000 + 3 * i; }

static PetscErrorCode SceneBuild(MPI_Comm comm, KergsScene *scene)
{
  KergsScene s;
  PetscReal  x[KERGS_DIM * NDISKS], v[KERGS_DIM * NDISKS], radius[NDISKS];
  PetscInt   material[NDISKS];

  PetscFunctionBeginUser;
  PetscCall(KergsSceneCreate(comm, &s));
  PetscCall(PetscStrncpy(s->name, "iotest", sizeof(s->name)));
  PetscCall(PetscFree(s->density));
  PetscCall(PetscFree(s->mu));
  s->nmaterials = 2;
  PetscCall(PetscCalloc1(2, &s->density));
  PetscCall(PetscCalloc1(4, &s->mu));
  s->density[0] = s->density[1] = 1.0;
  s->nwalls                     = NWALLS;
  PetscCall(PetscCalloc1(NWALLS, &s->walls));
  for (PetscInt w = 0; w < NWALLS; w++) {
    s->walls[w].a[0]     = -1.0 + w * 16.0;
    s->walls[w].a[1]     = w ? 2.0 : -2.0;
    s->walls[w].b[0]     = -1.0 + w * 16.0;
    s->walls[w].b[1]     = w ? -2.0 : 2.0;
    s->walls[w].infinite = (PetscBool)(w == 1);
  }
  for (PetscInt i = 0; i < NDISKS; i++) {
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      x[KERGS_DIM * i + d] = DiskX(i, d, 0);
      v[KERGS_DIM * i + d] = DiskV(i, d);
    }
    radius[i]   = DiskRadius(i);
    material[i] = DiskMaterial(i);
  }
  PetscCall(KergsSceneSetDisks(s, NDISKS, x, radius, material, v));
  for (PetscInt i = 0; i < s->nowned; i++) {
    const PetscInt g = s->dstart + i;
    s->rot[i]        = DiskRot(g);
    s->omega[i]      = DiskOmega(g);
    s->id[i]         = DiskId(g);
  }
  PetscCall(KergsSceneUpdateGhosts(s, PETSC_TRUE)); /* after the ids: ghosts carry them */
  s->frictional = PETSC_TRUE;                       /* tangential impulses are written */
  s->step       = 0;
  s->time       = 1.0 / 3.0;
  *scene        = s;
  PetscFunctionReturn(0);
}

/* Local index (owned or ghost) of the disk of global index g, or -1. */
static PetscInt LocalIndexOf(KergsScene s, PetscInt g)
{
  for (PetscInt i = 0; i < s->nlocal; i++)
    if (s->gidx[i] == g) return i;
  return -1;
}

/* Global contact g: g < NDISKS - 1 is disk-disk (g, g+1); g = NDISKS - 1 is disk 0 on wall 0, with a and b as
   global disk indices. Ids increase with the index, so the owner of disk a (the smaller id) owns the contact;
   sorted by (a, kind, idb) as in detect. */
static void ContactOfGlobal(PetscInt g, PetscInt step, KergsContact *c)
{
  memset(c, 0, sizeof(*c));
  if (g < NDISKS - 1) {
    c->kind = KERGS_CONTACT_DISK_DISK;
    c->a    = g;
    c->b    = g + 1;
    c->idb  = DiskId(g + 1);
    c->n[0] = -1.0;
  } else {
    c->kind = KERGS_CONTACT_DISK_WALL;
    c->a    = 0;
    c->b    = 0;
    c->idb  = 0;
    c->n[0] = 1.0;
  }
  c->t[0] = -c->n[1];
  c->t[1] = c->n[0];
  c->gap  = -1e-3 * (g + 1) / 3.0;
  c->mu   = 0.3 + 0.01 * g;
  c->r[0] = 0.5 + g + step / 3.0;
  c->r[1] = 0.1 * g - 1.0 / 7.0;
}

/* Global order of contacts: by disk a, then disk-disk before disk-wall. */
static PetscInt ContactGlobalAt(PetscInt pos)
{
  /* positions: contact (0,1), wall contact of disk 0, (1,2), (2,3), ... */
  if (pos == 0) return 0;
  if (pos == 1) return NDISKS - 1;
  return pos - 1;
}

static PetscErrorCode ContactsBuild(KergsScene scene, PetscInt step, KergsContacts *contacts)
{
  KergsContacts ct;
  PetscInt      n = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(1, &ct));
  ct->comm = scene->comm;
  PetscCall(PetscCalloc1(NDISKS, &ct->c));
  ct->nalloc  = NDISKS;
  ct->start   = -1;
  ct->nglobal = NDISKS;
  for (PetscInt pos = 0; pos < NDISKS; pos++) {
    KergsContact c;
    ContactOfGlobal(ContactGlobalAt(pos), step, &c);
    if (c.a >= scene->dstart && c.a < scene->dend) {
      if (ct->start < 0) ct->start = pos;
      /* local indices: a owned, b owned or a ghost */
      if (c.kind == KERGS_CONTACT_DISK_DISK) {
        const PetscInt gb = c.b;
        c.b               = LocalIndexOf(scene, gb);
        PetscCheck(c.b >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                   "disk %" PetscInt_FMT " of contact (%" PetscInt_FMT ", %" PetscInt_FMT ") is neither owned nor a ghost here", gb, c.a,
                   gb);
        PetscCheck(scene->id[c.b] == c.idb, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                   "disk %" PetscInt_FMT " has grain id %" PetscInt_FMT ", expected %" PetscInt_FMT, gb, scene->id[c.b], c.idb);
      }
      c.a        = c.a - scene->dstart;
      ct->c[n++] = c;
    }
  }
  ct->n = n;
  if (ct->start < 0) ct->start = 0;
  *contacts = ct;
  PetscFunctionReturn(0);
}

static PetscErrorCode ContactsFree(KergsContacts *ct)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree((*ct)->c));
  PetscCall(PetscFree(*ct));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Reading back with PetscViewerHDF5 */

/* Load dataset name of the current group into a new array replicated on every rank (N entries). */
static PetscErrorCode LoadAll(PetscViewer viewer, MPI_Comm comm, const char name[], PetscInt N, PetscInt bs, PetscReal **all)
{
  Vec                vec, seq;
  VecScatter         toall;
  const PetscScalar *a;

  PetscFunctionBeginUser;
  PetscCall(VecCreate(comm, &vec));
  PetscCall(VecSetSizes(vec, PETSC_DECIDE, N));
  PetscCall(VecSetBlockSize(vec, bs));
  PetscCall(VecSetType(vec, VECMPI));
  PetscCall(PetscObjectSetName((PetscObject)vec, name));
  PetscCall(VecLoad(vec, viewer));
  PetscCall(VecScatterCreateToAll(vec, &toall, &seq));
  PetscCall(VecScatterBegin(toall, vec, seq, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(toall, vec, seq, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(PetscMalloc1(N, all));
  PetscCall(VecGetArrayRead(seq, &a));
  for (PetscInt i = 0; i < N; i++) (*all)[i] = PetscRealPart(a[i]);
  PetscCall(VecRestoreArrayRead(seq, &a));
  PetscCall(VecScatterDestroy(&toall));
  PetscCall(VecDestroy(&seq));
  PetscCall(VecDestroy(&vec));
  PetscFunctionReturn(0);
}

/* Shape of dataset path (absolute) as HDF5 stores it (ndims -1 when there is no such dataset). */
static PetscErrorCode DatasetShape(PetscViewer viewer, const char path[], int *ndims, hsize_t dims[2])
{
  hid_t file, dset, space;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5GetFileId(viewer, &file));
  dset    = H5Dopen2(file, path, H5P_DEFAULT);
  dims[0] = dims[1] = 0;
  *ndims            = -1; /* no such dataset: the caller's check fails */
  if (dset < 0) PetscFunctionReturn(0);
  space   = H5Dget_space(dset);
  *ndims  = H5Sget_simple_extent_ndims(space);
  dims[0] = dims[1] = 0;
  if (*ndims >= 1 && *ndims <= 2) H5Sget_simple_extent_dims(space, dims, NULL);
  H5Sclose(space);
  H5Dclose(dset);
  PetscFunctionReturn(0);
}

static PetscBool SameArray(const PetscReal *a, const PetscReal *b, PetscInt n)
{
  for (PetscInt i = 0; i < n; i++)
    if (a[i] != b[i]) return PETSC_FALSE;
  return PETSC_TRUE;
}

/* ------------------------------------------------------------------------------------------------ */
/* Results file */

#define NSTEPS 5

static PetscReal StatEnergy(PetscInt k) { return 1.0 / (k + 3.0); }

/* Writes NSTEPS steps with -output_every 2: snapshots at steps 0, 2, 4 and the last (5). */
static PetscErrorCode WriteResults(KergsScene scene, const char path[])
{
  KergsResults  res;
  KergsContacts ct;
  PetscBool     due;

  PetscFunctionBeginUser;
  PetscCall(PetscOptionsSetValue(NULL, "-output", path));
  PetscCall(PetscOptionsSetValue(NULL, "-output_every", "2"));
  PetscCall(KergsResultsCreate(scene->comm, &res));
  PetscCall(KergsResultsSetFromOptions(res));
  PetscCall(KergsResultsOpen(res));
  for (PetscInt k = 0; k <= NSTEPS; k++) {
    scene->step = k;
    scene->time = k * 0.1 + 1.0 / 3.0;
    for (PetscInt i = 0; i < scene->nowned; i++) scene->x[KERGS_DIM * i] = DiskX(scene->dstart + i, 0, k);
    PetscCall(ContactsBuild(scene, k, &ct));
    PetscCall(KergsResultsSnapshotDue(res, k, (PetscBool)(k == NSTEPS), &due));
    if (due) {
      PetscCall(KergsResultsSnapshot(res, scene, ct));
      PetscCall(KergsResultsSnapshot(res, scene, ct)); /* same step again: ignored */
    }
    PetscCall(ContactsFree(&ct));
    if (k == NSTEPS) break;
    PetscCall(KergsResultsRecord(res, "step", (PetscReal)k));
    PetscCall(KergsResultsRecord(res, "energy", StatEnergy(k)));
    if (k >= 2) PetscCall(KergsResultsRecord(res, "late", -StatEnergy(k)));
    PetscCall(KergsResultsEndStep(res));
  }
  PetscCall(KergsResultsClose(res));
  PetscCall(KergsResultsDestroy(&res));
  PetscCall(PetscOptionsClearValue(NULL, "-output"));
  PetscCall(PetscOptionsClearValue(NULL, "-output_every"));
  PetscFunctionReturn(0);
}

static PetscErrorCode CheckStats(PetscViewer viewer, MPI_Comm comm)
{
  PetscReal *step, *energy, *late;
  PetscBool  ok = PETSC_TRUE, nanfill = PETSC_TRUE;
  int        ndims;
  hsize_t    dims[2];
  PetscInt   nrows = -1;

  PetscFunctionBeginUser;
  PetscCall(DatasetShape(viewer, "/stats/energy", &ndims, dims));
  PetscCall(CheckAll(comm, (PetscBool)(ndims == 1 && dims[0] == NSTEPS), "stats: /stats/energy is a 1-D dataset of one entry per step",
                     (PetscReal)dims[0], NSTEPS));
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, "/stats", "nrows", PETSC_INT, NULL, &nrows));
  PetscCall(CheckAll(comm, (PetscBool)(nrows == NSTEPS), "stats: attribute nrows = number of steps", nrows, NSTEPS));
  PetscCall(PetscViewerHDF5PushGroup(viewer, "/stats"));
  PetscCall(LoadAll(viewer, comm, "step", NSTEPS, 1, &step));
  PetscCall(LoadAll(viewer, comm, "energy", NSTEPS, 1, &energy));
  PetscCall(LoadAll(viewer, comm, "late", NSTEPS, 1, &late));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  for (PetscInt k = 0; k < NSTEPS; k++) {
    if (step[k] != (PetscReal)k || energy[k] != StatEnergy(k)) ok = PETSC_FALSE;
    if (k < 2 && !PetscIsNanReal(late[k])) nanfill = PETSC_FALSE;
    if (k >= 2 && late[k] != -StatEnergy(k)) nanfill = PETSC_FALSE;
  }
  PetscCall(CheckAll(comm, ok, "stats: step and energy read back exactly (VecLoad)", ok, 1));
  PetscCall(CheckAll(comm, nanfill, "stats: a statistic added at step 2 is NaN before, exact after", nanfill, 1));
  PetscCall(PetscFree(step));
  PetscCall(PetscFree(energy));
  PetscCall(PetscFree(late));
  PetscFunctionReturn(0);
}

/* The last snapshot (k = 3, step 5): positions, radii, walls, contacts and impulses. */
static PetscErrorCode CheckSnapshot(PetscViewer viewer, KergsScene scene)
{
  MPI_Comm  comm = scene->comm;
  PetscInt  step = -1, nsnap = -1, ncontacts = -1, nsnapattr = -1;
  PetscReal time = -1, *x, *radius, *walls, *id, *r, *a, *b, *kind, xexp[KERGS_DIM * NDISKS];
  PetscBool has, okr = PETSC_TRUE, okab = PETSC_TRUE, ok;
  int       ndims;
  hsize_t   dims[2];

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5HasGroup(viewer, "/snapshots/000003", &has));
  nsnap = has ? 4 : 0;
  PetscCall(PetscViewerHDF5HasGroup(viewer, "/snapshots/000004", &has));
  if (has) nsnap = 5;
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, "/", "nsnapshots", PETSC_INT, NULL, &nsnapattr));
  PetscCall(CheckAll(comm, (PetscBool)(nsnap == 4 && nsnapattr == 4),
                     "snapshots: -output_every 2 over 5 steps gives 4 (steps 0, 2, 4, 5), repeats ignored", nsnapattr, 4));
  PetscCall(PetscViewerHDF5PushGroup(viewer, "/snapshots/000003"));
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, NULL, "step", PETSC_INT, NULL, &step));
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, NULL, "time", PETSC_REAL, NULL, &time));
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, NULL, "ncontacts", PETSC_INT, NULL, &ncontacts));
  PetscCall(CheckAll(comm, (PetscBool)(step == NSTEPS && time == NSTEPS * 0.1 + 1.0 / 3.0 && ncontacts == NDISKS),
                     "snapshot: attributes step, time, ncontacts (step)", step, NSTEPS));
  PetscCall(LoadAll(viewer, comm, "x", KERGS_DIM * NDISKS, KERGS_DIM, &x));
  PetscCall(LoadAll(viewer, comm, "radius", NDISKS, 1, &radius));
  PetscCall(LoadAll(viewer, comm, "id", NDISKS, 1, &id));
  PetscCall(LoadAll(viewer, comm, "walls", NWALLS * 2 * KERGS_DIM, 2 * KERGS_DIM, &walls));
  PetscCall(LoadAll(viewer, comm, "r", KERGS_MAXCOMP * NDISKS, KERGS_MAXCOMP, &r));
  PetscCall(LoadAll(viewer, comm, "a", NDISKS, 1, &a));
  PetscCall(LoadAll(viewer, comm, "b", NDISKS, 1, &b));
  PetscCall(LoadAll(viewer, comm, "kind", NDISKS, 1, &kind));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  for (PetscInt i = 0; i < NDISKS; i++)
    for (PetscInt d = 0; d < KERGS_DIM; d++) xexp[KERGS_DIM * i + d] = DiskX(i, d, NSTEPS);
  ok = SameArray(x, xexp, KERGS_DIM * NDISKS);
  PetscCall(CheckAll(comm, ok, "snapshot: positions of step 5 round-trip exactly", ok, 1));
  {
    PetscReal radall[NDISKS];
    PetscCall(KergsSceneAllGatherReal(scene, scene->radius, 1, radall));
    ok = SameArray(radius, radall, NDISKS);
    PetscCall(CheckAll(comm, ok, "snapshot: radii round-trip exactly", ok, 1));
  }
  {
    PetscBool okid = PETSC_TRUE;
    PetscInt  idall[NDISKS];
    PetscCall(KergsSceneAllGatherInt(scene, scene->id, 1, idall));
    for (PetscInt i = 0; i < NDISKS; i++)
      if (id[i] != (PetscReal)idall[i] || idall[i] != DiskId(i)) okid = PETSC_FALSE;
    PetscCall(CheckAll(comm, okid, "snapshot: grain ids (stored as reals) round-trip", okid, 1));
  }
  ok = (PetscBool)(walls[0] == -1.0 && walls[3] == 2.0 && walls[4] == 15.0 && walls[7] == -2.0);
  PetscCall(CheckAll(comm, ok, "snapshot: walls hold endpoints a, b per row", ok, 1));
  for (PetscInt pos = 0; pos < NDISKS; pos++) {
    KergsContact c;
    ContactOfGlobal(ContactGlobalAt(pos), NSTEPS, &c);
    if (r[KERGS_MAXCOMP * pos] != c.r[0] || r[KERGS_MAXCOMP * pos + 1] != c.r[1]) okr = PETSC_FALSE;
    if (a[pos] != c.a || b[pos] != c.b || kind[pos] != (c.kind == KERGS_CONTACT_DISK_WALL ? 1.0 : 0.0)) okab = PETSC_FALSE;
  }
  PetscCall(CheckAll(comm, okr, "snapshot: contact impulses (normal, tangential) round-trip exactly, in global contact order", okr, 1));
  PetscCall(CheckAll(comm, okab, "snapshot: contact bodies a, b (global disk indices) and kinds round-trip", okab, 1));
  PetscCall(DatasetShape(viewer, "/snapshots/000003/x", &ndims, dims));
  PetscCall(CheckAll(comm, (PetscBool)(ndims == 2 && dims[0] == NDISKS && dims[1] == KERGS_DIM),
                     "snapshot: x is stored as (ndisks, 2) (dimensions)", ndims, 2));
  PetscCall(DatasetShape(viewer, "/snapshots/000003/r", &ndims, dims));
  PetscCall(CheckAll(comm, (PetscBool)(ndims == 2 && dims[0] == NDISKS && dims[1] == KERGS_MAXCOMP),
                     "snapshot: r is stored as (ncontacts, 2) (dimensions)", ndims, 2));
  PetscCall(PetscFree(x));
  PetscCall(PetscFree(radius));
  PetscCall(PetscFree(id));
  PetscCall(PetscFree(walls));
  PetscCall(PetscFree(r));
  PetscCall(PetscFree(a));
  PetscCall(PetscFree(b));
  PetscCall(PetscFree(kind));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestResults(KergsScene scene, const char dir[])
{
  MPI_Comm     comm = scene->comm;
  char         path[PETSC_MAX_PATH_LEN], tmp[PETSC_MAX_PATH_LEN];
  PetscBool    exists, tmpexists;
  PetscViewer  viewer;
  KergsResults res;

  PetscFunctionBeginUser;
  PetscCall(PetscPrintf(comm, "results file\n"));
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/sub/results.h5", dir));
  PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp", path));
  PetscCall(WriteResults(scene, path));
  PetscCall(FileExists(comm, path, &exists));
  PetscCall(FileExists(comm, tmp, &tmpexists));
  PetscCall(
      CheckAll(comm, (PetscBool)(exists && !tmpexists), "close: the final file exists (directory created), the .tmp does not", exists, 1));
  PetscCall(PetscViewerHDF5Open(comm, path, FILE_MODE_READ, &viewer));
  PetscCall(CheckStats(viewer, comm));
  PetscCall(CheckSnapshot(viewer, scene));
  PetscCall(PetscViewerDestroy(&viewer));

  /* a run that dies before Close leaves only the temporary file */
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/died.h5", dir));
  PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp", path));
  PetscCall(PetscOptionsSetValue(NULL, "-output", path));
  PetscCall(KergsResultsCreate(comm, &res));
  PetscCall(KergsResultsSetFromOptions(res));
  PetscCall(KergsResultsOpen(res));
  PetscCall(KergsResultsRecord(res, "step", 0.0));
  PetscCall(KergsResultsEndStep(res));
  PetscCall(KergsResultsDestroy(&res));
  PetscCall(FileExists(comm, path, &exists));
  PetscCall(FileExists(comm, tmp, &tmpexists));
  PetscCall(CheckAll(comm, (PetscBool)(!exists && tmpexists), "not closed: only the .tmp is left", tmpexists, 1));

  /* -output_none: no file at all */
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/none.h5", dir));
  PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp", path));
  PetscCall(PetscOptionsSetValue(NULL, "-output", path));
  PetscCall(PetscOptionsSetValue(NULL, "-output_none", "1"));
  PetscCall(KergsResultsCreate(comm, &res));
  PetscCall(KergsResultsSetFromOptions(res));
  PetscCall(KergsResultsOpen(res));
  PetscCall(KergsResultsRecord(res, "step", 0.0));
  PetscCall(KergsResultsEndStep(res));
  PetscCall(KergsResultsSnapshot(res, scene, NULL));
  PetscCall(KergsResultsClose(res));
  PetscCall(KergsResultsDestroy(&res));
  PetscCall(PetscOptionsClearValue(NULL, "-output"));
  PetscCall(PetscOptionsClearValue(NULL, "-output_none"));
  PetscCall(FileExists(comm, path, &exists));
  PetscCall(FileExists(comm, tmp, &tmpexists));
  PetscCall(CheckAll(comm, (PetscBool)(!exists && !tmpexists), "-output_none: no results file (nor .tmp)", exists + tmpexists, 0));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Sample */

/* A scene from KergsSceneCreate with the two materials of the hand-built one. */
static PetscErrorCode TargetSceneCreate(MPI_Comm comm, KergsScene *scene)
{
  PetscFunctionBeginUser;
  PetscCall(KergsSceneCreate(comm, scene));
  PetscCall(PetscFree((*scene)->density));
  PetscCall(PetscFree((*scene)->mu));
  (*scene)->nmaterials = 2;
  PetscCall(PetscMalloc1(2, &(*scene)->density));
  PetscCall(PetscCalloc1(4, &(*scene)->mu));
  (*scene)->density[0] = (*scene)->density[1] = 1.0;
  PetscFunctionReturn(0);
}

/* Reading path must fail with a PETSc error whose message names the file (and contains needle, when given); the scene
   keeps its disks. */
static PetscErrorCode CheckReadError(KergsScene target, const char path[], const char what[], const char needle[])
{
  PetscErrorCode ierr;
  char          *specific = NULL;
  const char    *base     = strrchr(path, '/') ? strrchr(path, '/') + 1 : path;
  PetscInt       before   = target->ndisks;
  PetscBool      named;
  char           line[PETSC_MAX_PATH_LEN + 256];

  PetscFunctionBeginUser;
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = KergsSampleRead(target, path);
  PetscCall(PetscPopErrorHandler());
  if (ierr) PetscCall(PetscErrorMessage(ierr, NULL, &specific));
  named = (PetscBool)(ierr != 0 && specific && strstr(specific, base) && (!needle || strstr(specific, needle)));
  PetscCall(PetscSNPrintf(line, sizeof(line), "sample: %s is refused, the message naming the file%s%s%s", what, needle ? " and \"" : "",
                          needle ? needle : "", needle ? "\"" : ""));
  PetscCall(CheckAll(target->comm, named, line, ierr != 0, 1));
  if (specific) PetscCall(PetscPrintf(target->comm, "      (%s)\n", specific));
  PetscCall(CheckAll(target->comm, (PetscBool)(target->ndisks == before), "sample: a failed read leaves the scene's disks unchanged",
                     target->ndisks, before));
  PetscFunctionReturn(0);
}

/* The scene written with the grain id of the disk of global index g replaced by id (on its owner), then restored. */
static PetscErrorCode WriteSampleWithId(KergsScene scene, const char path[], PetscInt g, PetscInt id)
{
  PetscInt saved = -1;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < scene->nowned; i++)
    if (scene->dstart + i == g) {
      saved        = scene->id[i];
      scene->id[i] = id;
    }
  PetscCall(KergsSampleWrite(scene, NULL, path));
  for (PetscInt i = 0; i < scene->nowned; i++)
    if (scene->dstart + i == g) scene->id[i] = saved;
  PetscFunctionReturn(0);
}

/* Every disk of a scene of NDISKS disks, gathered in global-index order on every rank. */
static PetscErrorCode GatherDisks(KergsScene s, Disks *all)
{
  PetscFunctionBeginUser;
  PetscCheck(s->ndisks == NDISKS, s->comm, PETSC_ERR_PLIB, "scene %s has %" PetscInt_FMT " disks, not %d", s->name, s->ndisks, NDISKS);
  PetscCall(DisksGather(s, all));
  PetscFunctionReturn(0);
}

/* Rank 0 writes the first half of src's bytes to dst. */
static PetscErrorCode TruncatedCopy(MPI_Comm comm, const char src[], const char dst[])
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    FILE *in = fopen(src, "rb"), *out = fopen(dst, "wb");
    long  size;
    char *buf;
    PetscCheck(in && out, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot copy %s to %s", src, dst);
    fseek(in, 0, SEEK_END);
    size = ftell(in);
    fseek(in, 0, SEEK_SET);
    PetscCall(PetscMalloc1(size, &buf));
    PetscCheck(fread(buf, 1, (size_t)size, in) == (size_t)size, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "Cannot read %s", src);
    PetscCheck(fwrite(buf, 1, (size_t)(size / 2), out) == (size_t)(size / 2), PETSC_COMM_SELF, PETSC_ERR_FILE_WRITE, "Cannot write %s",
               dst);
    PetscCall(PetscFree(buf));
    fclose(in);
    fclose(out);
  }
  PetscCallMPI(MPI_Barrier(comm));
  PetscFunctionReturn(0);
}

static PetscErrorCode WriteText(MPI_Comm comm, const char path[])
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    FILE *f = fopen(path, "w");
    PetscCheck(f, PETSC_COMM_SELF, PETSC_ERR_FILE_OPEN, "Cannot write %s", path);
    fprintf(f, "x y radius\n0 0 1\n");
    fclose(f);
  }
  PetscCallMPI(MPI_Barrier(comm));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestSample(KergsScene scene, const char dir[])
{
  MPI_Comm   comm = scene->comm;
  char       path[PETSC_MAX_PATH_LEN], bad[PETSC_MAX_PATH_LEN];
  KergsScene target;
  PetscBool  ok = PETSC_TRUE, exists;

  PetscFunctionBeginUser;
  PetscCall(PetscPrintf(comm, "sample file\n"));
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/sample.h5", dir));
  scene->time = 2.0 / 3.0;
  PetscCall(KergsSampleWrite(scene, NULL, path));
  PetscCall(PetscSNPrintf(bad, sizeof(bad), "%s.tmp", path));
  PetscCall(FileExists(comm, bad, &exists));
  PetscCall(CheckAll(comm, (PetscBool)!exists, "sample: written atomically (no .tmp left)", exists, 0));
  PetscCall(TargetSceneCreate(comm, &target));
  PetscCall(KergsSampleRead(target, path));
  { /* the file records the preparation's time; a run from it starts its own clock at 0 */
    PetscViewer v;
    PetscReal   recorded = -1.0;
    PetscCall(PetscViewerHDF5Open(comm, path, FILE_MODE_READ, &v));
    PetscCall(PetscViewerHDF5ReadAttribute(v, "/sample", "time", PETSC_REAL, NULL, &recorded));
    PetscCall(PetscViewerDestroy(&v));
    PetscCall(CheckAll(comm, (PetscBool)(recorded == scene->time && target->time == 0.0),
                       "sample: the file records the scene's time, and the scene read from it starts at 0", (PetscInt)(target->time == 0.0),
                       1));
  }
  ok = (PetscBool)(target->ndisks == NDISKS);
  if (ok) { /* both scenes gathered in global-index order */
    Disks want, got;
    PetscCall(GatherDisks(scene, &want));
    PetscCall(GatherDisks(target, &got));
    ok = (PetscBool)(SameArray(got.x, want.x, KERGS_DIM * NDISKS) && SameArray(got.v, want.v, KERGS_DIM * NDISKS) &&
                     SameArray(got.rot, want.rot, KERGS_NROT * NDISKS) && SameArray(got.omega, want.omega, KERGS_NROT * NDISKS) &&
                     SameArray(got.radius, want.radius, NDISKS));
    for (PetscInt i = 0; i < NDISKS; i++)
      if (got.id[i] != want.id[i] || got.material[i] != want.material[i]) ok = PETSC_FALSE;
    /* and the scene written was the one built: state of step 5, rot, omega, ids of the Disk* functions */
    for (PetscInt i = 0; i < NDISKS; i++) {
      if (want.x[KERGS_DIM * i] != DiskX(i, 0, NSTEPS) || want.rot[i] != DiskRot(i) || want.omega[i] != DiskOmega(i) ||
          want.id[i] != DiskId(i) || want.material[i] != DiskMaterial(i))
        ok = PETSC_FALSE;
    }
    PetscCall(DisksFree(&want));
    PetscCall(DisksFree(&got));
  }
  PetscCall(CheckAll(comm, ok, "sample: write/read round-trips x, v, rot, omega, radius, material, id exactly", ok, 1));

  PetscCall(PetscSNPrintf(bad, sizeof(bad), "%s/sample_half.h5", dir));
  PetscCall(TruncatedCopy(comm, path, bad));
  PetscCall(CheckReadError(target, bad, "a truncated file (first half of the bytes)", NULL));
  PetscCall(PetscSNPrintf(bad, sizeof(bad), "%s/no_such_sample.h5", dir));
  PetscCall(CheckReadError(target, bad, "a missing file", NULL));
  PetscCall(PetscSNPrintf(bad, sizeof(bad), "%s/sample_text.h5", dir));
  PetscCall(WriteText(comm, bad));
  PetscCall(CheckReadError(target, bad, "a text file", NULL));
  PetscCall(PetscSNPrintf(bad, sizeof(bad), "%s/sub/results.h5", dir));
  PetscCall(CheckReadError(target, bad, "an HDF5 file without /sample", NULL));
  /* grain ids identify grains (persistence, ownership, outputs): a repeated or a negative one is refused, by id */
  PetscCall(PetscSNPrintf(bad, sizeof(bad), "%s/sample_repeated_id.h5", dir));
  PetscCall(WriteSampleWithId(scene, bad, 4, DiskId(1)));
  PetscCall(CheckReadError(target, bad, "a repeated grain id (disk 4 with disk 1's id 1003)", "disks 1 and 4 have the same grain id 1003"));
  PetscCall(PetscSNPrintf(bad, sizeof(bad), "%s/sample_negative_id.h5", dir));
  PetscCall(WriteSampleWithId(scene, bad, 2, -5));
  PetscCall(CheckReadError(target, bad, "a negative grain id", "disk 2 has id -5"));
  PetscCall(KergsSceneDestroy(&target));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* FCLib export */

/* Hand-built W over contact components (global index i = contact * nc + comp): a symmetric band
   W_ii = 2 + i/10, W_i,i+1 = W_i+1,i = -1/3 - i/100, W_i,i+2 = 1/7 (coupling across contacts). */
static PetscReal WEntry(PetscInt i, PetscInt j)
{
  const PetscInt lo = PetscMin(i, j), d = PetscAbsInt(i - j);
  if (d == 0) return 2.0 + i / 10.0;
  if (d == 1) return -1.0 / 3.0 - lo / 100.0;
  if (d == 2) return 1.0 / 7.0;
  return 0.0;
}

static PetscReal VdEntry(PetscInt i) { return -1.0 - i / 30.0; }

/* Active flag of global contact position pos: every contact except position 2. */
static PetscBool ActiveAt(PetscInt pos) { return (PetscBool)(pos != 2); }

static PetscErrorCode OperatorsBuild(KergsContacts ct, PetscInt nc, KergsOperators *ops)
{
  KergsOperators o;
  PetscInt       lo, hi, N = ct->nglobal * nc;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(1, &o));
  o->comm  = ct->comm;
  o->ncomp = nc;
  PetscCall(MatCreateAIJ(ct->comm, ct->n * nc, ct->n * nc, N, N, 5, NULL, 4, NULL, &o->W));
  PetscCall(MatGetOwnershipRange(o->W, &lo, &hi));
  for (PetscInt i = lo; i < hi; i++)
    for (PetscInt j = PetscMax(0, i - 2); j <= PetscMin(N - 1, i + 2); j++) PetscCall(MatSetValue(o->W, i, j, WEntry(i, j), INSERT_VALUES));
  PetscCall(MatAssemblyBegin(o->W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(o->W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatCreateVecs(o->W, NULL, &o->vd));
  for (PetscInt i = lo; i < hi; i++) PetscCall(VecSetValue(o->vd, i, VdEntry(i), INSERT_VALUES));
  PetscCall(VecAssemblyBegin(o->vd));
  PetscCall(VecAssemblyEnd(o->vd));
  *ops = o;
  PetscFunctionReturn(0);
}

static PetscErrorCode OperatorsFree(KergsOperators *o)
{
  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&(*o)->W));
  PetscCall(VecDestroy(&(*o)->vd));
  PetscCall(PetscFree(*o));
  PetscFunctionReturn(0);
}

typedef struct fclib_local *(*ReadLocalFn)(const char *);
typedef struct fclib_solution *(*ReadSolutionFn)(const char *);
typedef void (*DeleteLocalFn)(struct fclib_local *);
typedef void (*DeleteSolutionsFn)(struct fclib_solution *, int);

/* Compare the file (read with libfclib's reader, rank 0) with the expected padded problem. */
static PetscErrorCode CheckFCLibFile(MPI_Comm comm, const char path[], PetscInt nc, PetscBool *ok, char why[], size_t len)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  *ok    = PETSC_TRUE;
  why[0] = 0;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    void                  *h = dlopen(KERGS_FCLIB_LIBRARY, RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
    ReadLocalFn            read_local;
    ReadSolutionFn         read_solution;
    DeleteLocalFn          delete_local;
    DeleteSolutionsFn      delete_solutions;
    struct fclib_local    *L;
    struct fclib_solution *S;
    PetscInt               act[NDISKS], na = 0, m;
    PetscReal             *dense, *expect;

    if (!h) h = dlopen("libfclib.so.0", RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
    PetscCheck(h, PETSC_COMM_SELF, PETSC_ERR_LIB, "Cannot dlopen libfclib: %s", dlerror());
    *(void **)&read_local       = dlsym(h, "fclib_read_local");
    *(void **)&read_solution    = dlsym(h, "fclib_read_solution");
    *(void **)&delete_local     = dlsym(h, "fclib_delete_local");
    *(void **)&delete_solutions = dlsym(h, "fclib_delete_solutions");
    PetscCheck(read_local && read_solution && delete_local && delete_solutions, PETSC_COMM_SELF, PETSC_ERR_LIB,
               "libfclib lacks its readers");
    for (PetscInt pos = 0; pos < NDISKS; pos++)
      if (ActiveAt(pos)) act[na++] = pos;
    m = 2 * na;
    L = read_local(path);
    S = read_solution(path);
    PetscCheck(L && S, PETSC_COMM_SELF, PETSC_ERR_FILE_READ, "libfclib cannot read %s", path);
    if (L->spacedim != 2 || L->W->m != m || L->W->n != m || L->W->nz != -1) {
      *ok = PETSC_FALSE;
      snprintf(why, len, "spacedim %d, W %d x %d, nz %d", L->spacedim, L->W->m, L->W->n, L->W->nz);
    }
    PetscCall(PetscCalloc2(m * m, &dense, m * m, &expect));
    for (int j = 0; *ok && j < m; j++) {
      if (L->W->p[j + 1] < L->W->p[j]) *ok = PETSC_FALSE;
      for (int e = L->W->p[j]; *ok && e < L->W->p[j + 1]; e++) {
        if (e > L->W->p[j] && L->W->i[e] <= L->W->i[e - 1]) *ok = PETSC_FALSE; /* sorted, no duplicates */
        dense[L->W->i[e] * m + j] = L->W->x[e];
      }
    }
    if (!*ok && !why[0]) snprintf(why, len, "CSC pointers or row indices not increasing");
    /* expected: W restricted to active contacts; frictionless: padded diagonal tangential rows */
    for (PetscInt a = 0; a < na; a++)
      for (PetscInt b = 0; b < na; b++)
        for (PetscInt ca = 0; ca < 2; ca++)
          for (PetscInt cb = 0; cb < 2; cb++) {
            PetscReal w = 0.0;
            if (ca < nc && cb < nc)
              w = WEntry(act[a] * nc + ca, act[b] * nc + cb);
            else if (nc == 1 && a == b && ca == 1 && cb == 1)
              w = WEntry(act[a], act[a]);
            expect[(2 * a + ca) * m + 2 * b + cb] = w;
          }
    if (*ok && !SameArray(dense, expect, m * m)) {
      *ok = PETSC_FALSE;
      snprintf(why, len, "W differs from the hand-built matrix");
    }
    for (PetscInt a = 0; *ok && a < na; a++) {
      KergsContact c;
      PetscReal    u[2];
      ContactOfGlobal(ContactGlobalAt(act[a]), 0, &c);
      if (L->q[2 * a] != VdEntry(act[a] * nc) || L->q[2 * a + 1] != (nc == 2 ? VdEntry(act[a] * nc + 1) : 0.0))
        snprintf(why, len, "q of contact %d", (int)a);
      else if (L->mu[a] != (nc == 2 ? c.mu : 0.0))
        snprintf(why, len, "mu of contact %d", (int)a);
      else if (S->r[2 * a] != c.r[0] || S->r[2 * a + 1] != (nc == 2 ? c.r[1] : 0.0))
        snprintf(why, len, "solution r of contact %d", (int)a);
      for (PetscInt ca = 0; !why[0] && ca < 2; ca++) { /* u = W r + q */
        u[ca] = L->q[2 * a + ca];
        for (PetscInt j = 0; j < m; j++) u[ca] += expect[(2 * a + ca) * m + j] * S->r[j];
        if (PetscAbsReal(u[ca] - S->u[2 * a + ca]) > 1e-14 * (1 + PetscAbsReal(u[ca])))
          snprintf(why, len, "solution u of contact %d", (int)a);
      }
      if (why[0]) *ok = PETSC_FALSE;
    }
    PetscCall(PetscFree2(dense, expect));
    delete_local(L);
    delete_solutions(S, 1);
  }
  PetscCallMPI(MPI_Bcast(ok, 1, MPIU_BOOL, 0, comm));
  PetscFunctionReturn(0);
}

static PetscErrorCode CheckFCLibEmpty(MPI_Comm comm, const char path[], PetscBool *ok)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  *ok = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    void               *h = dlopen(KERGS_FCLIB_LIBRARY, RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
    ReadLocalFn         read_local;
    DeleteLocalFn       delete_local;
    struct fclib_local *L;

    if (!h) h = dlopen("libfclib.so.0", RTLD_NOW | RTLD_LOCAL | RTLD_DEEPBIND);
    PetscCheck(h, PETSC_COMM_SELF, PETSC_ERR_LIB, "Cannot dlopen libfclib: %s", dlerror());
    *(void **)&read_local   = dlsym(h, "fclib_read_local");
    *(void **)&delete_local = dlsym(h, "fclib_delete_local");
    PetscCheck(read_local && delete_local, PETSC_COMM_SELF, PETSC_ERR_LIB, "libfclib lacks its readers");
    L   = read_local(path);
    *ok = (PetscBool)(L && L->spacedim == 2 && L->W->m == 0 && L->W->n == 0 && L->W->nz == -1 && L->W->p[0] == 0);
    if (L) delete_local(L);
  }
  PetscCallMPI(MPI_Bcast(ok, 1, MPIU_BOOL, 0, comm));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestFCLib(KergsScene scene, const char dir[])
{
  MPI_Comm       comm = scene->comm;
  KergsContacts  ct;
  KergsOperators ops;
  PetscBool     *active, ok, exists;
  char           path[PETSC_MAX_PATH_LEN], why[256], line[512];

  PetscFunctionBeginUser;
  PetscCall(PetscPrintf(comm, "FCLib export\n"));
  PetscCall(ContactsBuild(scene, 0, &ct));
  PetscCall(PetscMalloc1(ct->n, &active));
  for (PetscInt k = 0; k < ct->n; k++) active[k] = ActiveAt(ct->start + k);
  for (PetscInt nc = 2; nc >= 1; nc--) {
    PetscCall(OperatorsBuild(ct, nc, &ops));
    PetscCall(PetscSNPrintf(path, sizeof(path), "%s/fclib_nc%d.h5", dir, (int)nc));
    PetscCall(KergsFCLibExport(scene, ct, ops, active, path));
    PetscCall(FileExists(comm, path, &exists));
    PetscCall(PetscSNPrintf(line, sizeof(line), "fclib (%s): file %s written", nc == 2 ? "frictional" : "frictionless", path));
    PetscCall(CheckAll(comm, exists, line, exists, 1));
    PetscCall(CheckFCLibFile(comm, path, nc, &ok, why, sizeof(why)));
    PetscCall(PetscSNPrintf(line, sizeof(line),
                            "fclib (%s): fclib_read_local gives W (CSC, active contacts only%s), q, mu, r, u = W r + q %s",
                            nc == 2 ? "frictional" : "frictionless", nc == 1 ? ", tangential padded" : "", why));
    PetscCall(CheckAll(comm, ok, line, ok, 1));
    PetscCall(OperatorsFree(&ops));
  }
  /* no active contact: an empty problem (m = 0), still a valid FCLib file */
  for (PetscInt k = 0; k < ct->n; k++) active[k] = PETSC_FALSE;
  PetscCall(OperatorsBuild(ct, 2, &ops));
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/fclib_empty.h5", dir));
  PetscCall(KergsFCLibExport(scene, ct, ops, active, path));
  PetscCall(CheckFCLibEmpty(comm, path, &ok));
  PetscCall(CheckAll(comm, ok, "fclib: no active contact gives an empty problem (W 0 x 0) that libfclib reads back", ok, 1));
  PetscCall(OperatorsFree(&ops));
  PetscCall(PetscFree(active));
  PetscCall(ContactsFree(&ct));
  PetscFunctionReturn(0);
}

static PetscBool Close(PetscReal a, PetscReal b, PetscReal tol)
{
  return (PetscBool)(PetscAbsReal(a - b) <= tol * PetscMax(PetscAbsReal(a), PetscAbsReal(b)));
}

/* The contact forces a sample records come back as impulses of the reading scene's time step, each keyed to the same
   grains, and a wall contact to the wall of the same name whatever the walls' order. Written at dt 2e-3 with walls
   w0, w1; read at dt 5e-4 with walls w1, w0 (w0 is wall 1 there). The contact of disks 1 and 2 is written with
   r_n = -1e-21, zero to rounding as newton leaves some: it carries no force, so it is left out, and the file reads. */
static PetscErrorCode TestSampleForces(KergsScene scene, const char dir[])
{
  MPI_Comm        comm     = scene->comm;
  const char     *order[2] = {"w1", "w0"};
  const PetscReal dt0 = 2e-3, dt1 = 5e-4;
  char            path[PETSC_MAX_PATH_LEN];
  KergsContacts   written, read;
  KergsContact   *c;
  KergsScene      target;
  PetscInt        m, total;
  PetscBool       ok = PETSC_TRUE;

  PetscFunctionBeginUser;
  PetscCall(PetscPrintf(comm, "sample contact forces\n"));
  PetscCall(PetscSNPrintf(path, sizeof(path), "%s/sample_forces.h5", dir));
  for (PetscInt w = 0; w < scene->nwalls; w++) PetscCall(PetscSNPrintf(scene->walls[w].name, sizeof(scene->walls[w].name), "w%d", (int)w));
  scene->dt   = dt0;
  scene->step = 1; /* a packing a run has stepped: its contacts are written */
  PetscCall(ContactsBuild(scene, 0, &written));
  PetscCall(KergsContactsGetLocal(written, &m, &c));
  for (PetscInt k = 0; k < m; k++)
    if (c[k].kind == KERGS_CONTACT_DISK_DISK && c[k].a + scene->dstart == 1) c[k].r[0] = -1e-21, c[k].r[1] = 0.0;
  PetscCall(KergsSampleWrite(scene, written, path));
  PetscCall(ContactsFree(&written));
  PetscCall(TargetSceneCreate(comm, &target));
  target->dt     = dt1;
  target->nwalls = 2;
  PetscCall(PetscCalloc1(2, &target->walls));
  for (PetscInt w = 0; w < 2; w++) PetscCall(PetscStrncpy(target->walls[w].name, order[w], sizeof(target->walls[w].name)));
  PetscCall(KergsSampleRead(target, path));
  PetscCall(KergsContactsCreate(comm, &read));
  PetscCall(KergsSampleReadForces(target, read, NULL));
  PetscCall(KergsContactsGetLocal(read, &m, &c));
  for (PetscInt k = 0; k < m; k++) {
    KergsContact want;
    PetscInt     g = NDISKS - 1; /* the wall contact of disk 0 */

    if (c[k].kind == KERGS_CONTACT_DISK_DISK)
      for (PetscInt i = 0; i < NDISKS; i++)
        if (DiskId(i) == target->id[c[k].a]) g = i;
    ContactOfGlobal(g, 0, &want);
    ok = (PetscBool)(ok && g != 1 && target->id[c[k].a] == DiskId(want.a) && c[k].b == -1 &&
                     c[k].idb == (c[k].kind == KERGS_CONTACT_DISK_WALL ? 1 : want.idb) && Close(c[k].r[0], want.r[0] / dt0 * dt1, 1e-14) &&
                     Close(c[k].r[1], want.r[1] / dt0 * dt1, 1e-14));
  }
  PetscCallMPI(MPIU_Allreduce(&m, &total, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(CheckAll(comm, (PetscBool)(total == NDISKS - 1),
                     "sample forces: every contact with r_n > 0 comes back, on the owner of its grain a", total, NDISKS - 1));
  PetscCall(CheckAll(
      comm, ok, "sample forces: same keys, the wall matched by name (w0: wall 1 of the reader), impulse = force x the reader's dt", ok, 1));
  PetscCall(KergsContactsDestroy(&read));
  PetscCall(KergsSceneDestroy(&target));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KergsScene scene;
  char       dir[PETSC_MAX_PATH_LEN] = "test_io_out";

  PetscCall(PetscInitialize(&argc, &argv, NULL, "kergs io tests"));
  PetscCall(PetscOptionsGetString(NULL, NULL, "-dir", dir, sizeof(dir), NULL));
  {
    char probe[PETSC_MAX_PATH_LEN + 16];
    PetscCall(PetscSNPrintf(probe, sizeof(probe), "%s/probe", dir));
    PetscCall(KergsFileMakeParentDir(PETSC_COMM_WORLD, probe)); /* creates dir */
  }
  PetscCall(SceneBuild(PETSC_COMM_WORLD, &scene));
  /* FCLib first: PETSc's (parallel) HDF5 must still work after libfclib's serial HDF5 ran in this process */
  PetscCall(TestFCLib(scene, dir));
  PetscCall(TestResults(scene, dir));
  PetscCall(TestSample(scene, dir));
  PetscCall(TestSampleForces(scene, dir));
  PetscCall(KergsSceneDestroy(&scene));
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
