/* kergs sample: a packing of disks saved by one run, for another to start from (layout in docs/results.md; read by
   the scene's disk source "file", src/scene/sample_read.c), with the contact forces that hold it, which the run
   reading it takes as the warm start of its first step. Written through PetscViewerHDF5 to "<path>.tmp" and renamed
   when complete. */
#include <kergs/sample.h>
#include <kergs/results.h>
#include <kergs/files.h>
#include <kergs/private/h5probe.h>
#include <petscviewerhdf5.h>
#include <stdio.h>
#include <stdlib.h>

#define KERGS_SAMPLE_GROUP "/sample"
#define KERGS_CONTACTS_GROUP "/sample/contacts"

/* /sample/box: where the box walls stand, for -box_from_sample (a compaction's free walls end where the sample fits). */
static PetscErrorCode SampleWriteBox(PetscViewer viewer, KergsScene scene)
{
  PetscBool   has;
  PetscReal   box[4];
  MPI_Comm    comm;
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetBox(scene, &has, box));
  if (!has) PetscFunctionReturn(0);
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  PetscCall(KergsViewBlocks(viewer, comm, "box", rank ? 0 : 1, 4, box));
  PetscFunctionReturn(0);
}

/* /sample/contacts: every contact that carries a force at the end of the run, keyed as the warm start keys them (grain
   id of a, kind, grain id or wall index of b), with its force r / dt in the contact frame, so that a run of another
   time step reads the same forces. A contact carries a force when its normal impulse is positive (Coulomb bounds the
   tangential one by mu r_n): newton leaves some r_n at -1e-20, zero to rounding, which the reader would refuse. */
static PetscErrorCode SampleWriteContacts(PetscViewer viewer, KergsScene scene, KergsContacts contacts)
{
  KergsDisks    D;
  KergsContact *c;
  PetscInt      m, k = 0, total, *ida, *kind, *idb;
  PetscReal     dt, *force;
  char         *walls;
  MPI_Comm      comm;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(KergsSceneGetTimeStep(scene, &dt, NULL));
  PetscCall(KergsContactsGetLocal(contacts, &m, &c));
  PetscCall(PetscMalloc4(m + 1, &ida, m + 1, &kind, m + 1, &idb, KERGS_MAXCOMP * m + 1, &force));
  for (PetscInt i = 0; i < m; i++) {
    if (!(c[i].r[0] > 0.0)) continue;
    ida[k]  = D.id[c[i].a];
    kind[k] = c[i].kind == KERGS_CONTACT_DISK_WALL ? 1 : 0;
    idb[k]  = c[i].idb;
    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) force[KERGS_MAXCOMP * k + j] = c[i].r[j] / dt;
    k++;
  }
  PetscCallMPI(MPI_Allreduce(&k, &total, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(KergsSceneGetWallNames(scene, &walls)); /* a wall contact's b_id indexes this list */
  PetscCall(PetscViewerHDF5PushGroup(viewer, KERGS_CONTACTS_GROUP));
  PetscCall(PetscViewerHDF5WriteAttribute(viewer, NULL, "ncontacts", PETSC_INT, &total));
  PetscCall(PetscViewerHDF5WriteAttribute(viewer, NULL, "walls", PETSC_STRING, walls));
  PetscCall(KergsViewIntegers(viewer, comm, "a_id", k, ida));
  PetscCall(KergsViewIntegers(viewer, comm, "kind", k, kind));
  PetscCall(KergsViewIntegers(viewer, comm, "b_id", k, idb));
  PetscCall(KergsViewBlocks(viewer, comm, "force", k, KERGS_MAXCOMP, force));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  PetscCall(PetscFree(walls));
  PetscCall(PetscFree4(ida, kind, idb, force));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSampleWrite(KergsScene scene, KergsContacts contacts, const char path[])
{
  KergsDisks  D;
  PetscInt    step;
  PetscReal   sctime;
  char        tmp[PETSC_MAX_PATH_LEN];
  PetscViewer viewer;
  MPI_Comm    comm;
  PetscInt    n, nl;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(KergsSceneGetStep(scene, &step, &sctime, NULL));
  n  = D.ndisks;
  nl = D.nowned;
  PetscCall(KergsInitializePackage());
  PetscCheck(path && path[0], comm, PETSC_ERR_ARG_WRONG, "Sample file name is empty");
  PetscCall(PetscSNPrintf(tmp, sizeof(tmp), "%s.tmp", path));
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(KergsFileMakeParentDir(comm, path));
  PetscCall(PetscViewerHDF5Open(comm, tmp, FILE_MODE_WRITE, &viewer));
  PetscCall(PetscViewerHDF5SetBaseDimension2(viewer, PETSC_FALSE)); /* the documented layout: 1-D scalars, float64 */
  PetscCall(PetscViewerHDF5SetSPOutput(viewer, PETSC_FALSE));
  PetscCall(PetscViewerHDF5WriteAttribute(viewer, "/", "kergs_format", PETSC_STRING, KERGS_SAMPLE_FORMAT));
  PetscCall(PetscViewerHDF5PushGroup(viewer, KERGS_SAMPLE_GROUP));
  PetscCall(PetscViewerHDF5WriteAttribute(viewer, NULL, "ndisks", PETSC_INT, &n));
  PetscCall(PetscViewerHDF5WriteAttribute(viewer, NULL, "time", PETSC_REAL, &sctime));
  PetscCall(PetscViewerHDF5WriteAttribute(viewer, NULL, "dim", PETSC_INT, &(PetscInt){KERGS_DIM}));
  /* each rank writes its owned disks, global indices [dstart, dend), in rank order */
  PetscCall(KergsViewBlocks(viewer, comm, "x", nl, KERGS_DIM, D.x));
  PetscCall(KergsViewBlocks(viewer, comm, "v", nl, KERGS_DIM, D.v));
  PetscCall(KergsViewBlocks(viewer, comm, "rot", nl, KERGS_NROT, D.rot));
  PetscCall(KergsViewBlocks(viewer, comm, "omega", nl, KERGS_NROT, D.omega));
  PetscCall(KergsViewBlocks(viewer, comm, "radius", nl, 1, D.radius));
  PetscCall(KergsViewIntegers(viewer, comm, "material", nl, D.material));
  PetscCall(KergsViewIntegers(viewer, comm, "id", nl, D.id));
  PetscCall(SampleWriteBox(viewer, scene));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  /* a run that took no step has no contacts of its own yet: it writes none, rather than an empty list that would read as
     a packing carrying no force */
  if (contacts && step > 0) PetscCall(SampleWriteContacts(viewer, scene, contacts));
  PetscCall(PetscViewerDestroy(&viewer));
  PetscCall(KergsFileCommit(comm, tmp, path));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* The index, among the reading scene's walls, of each wall the file's contacts name (-1: the scene has no such wall). */
static PetscErrorCode MapWalls(PetscViewer viewer, const char path[], KergsScene scene, PetscInt *nfile, PetscInt **map)
{
  PetscInt         nwalls;
  const KergsWall *walls;
  char            *names = NULL, **list;
  int              argc;
  MPI_Comm         comm;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetWalls(scene, &nwalls, &walls));
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, KERGS_CONTACTS_GROUP, "walls", PETSC_STRING, NULL, &names)); /* probed: one string */
  PetscCall(PetscStrToArray(names, ',', &argc, &list));
  PetscCall(PetscMalloc1(argc + 1, map));
  for (int k = 0; k < argc; k++) {
    for (int j = 0; j < k; j++) {
      PetscBool same;

      PetscCall(PetscStrcmp(list[j], list[k], &same));
      PetscCheck(!same, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: the attribute walls of %s names the wall %s twice", path,
                 KERGS_CONTACTS_GROUP, list[k]);
    }
    (*map)[k] = -1;
    for (PetscInt w = 0; w < nwalls; w++) {
      PetscBool same;

      PetscCall(PetscStrcmp(list[k], walls[w].name, &same));
      if (same) (*map)[k] = w;
    }
  }
  *nfile = argc;
  PetscCall(PetscStrToArrayDestroy(argc, list));
  PetscCall(PetscFree(names));
  PetscFunctionReturn(0);
}

static int CompareKeys(const void *p, const void *q) { return KERGS_COMPARE_KEYS((const KergsContact *)p, (const KergsContact *)q); }

/* /sample/contacts as read from the file, every record on every rank. */
typedef struct {
  PetscInt   n, nwalls, *wall; /* wall[k]: the reading scene's index of the file's wall k, -1 when it has none */
  PetscReal *ida, *kind, *idb, *force;
} SampleContacts;

static PetscErrorCode SampleContactsFree(SampleContacts *sc)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(sc->wall));
  PetscCall(PetscFree(sc->ida));
  PetscCall(PetscFree(sc->kind));
  PetscCall(PetscFree(sc->idb));
  PetscCall(PetscFree(sc->force));
  PetscFunctionReturn(0);
}

static PetscErrorCode SampleContactsLoad(PetscViewer viewer, const char path[], KergsScene scene, SampleContacts *sc)
{
  MPI_Comm comm;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, KERGS_CONTACTS_GROUP, "ncontacts", PETSC_INT, NULL, &sc->n));
  PetscCheck(sc->n >= 0, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: %s has %" PetscInt_FMT " contacts", path, KERGS_CONTACTS_GROUP,
             sc->n);
  PetscCall(MapWalls(viewer, path, scene, &sc->nwalls, &sc->wall));
  PetscCall(PetscViewerHDF5PushGroup(viewer, KERGS_CONTACTS_GROUP));
  PetscCall(KergsLoadAllBlocks(viewer, comm, path, KERGS_CONTACTS_GROUP, "a_id", sc->n, 1, &sc->ida));
  PetscCall(KergsLoadAllBlocks(viewer, comm, path, KERGS_CONTACTS_GROUP, "kind", sc->n, 1, &sc->kind));
  PetscCall(KergsLoadAllBlocks(viewer, comm, path, KERGS_CONTACTS_GROUP, "b_id", sc->n, 1, &sc->idb));
  PetscCall(KergsLoadAllBlocks(viewer, comm, path, KERGS_CONTACTS_GROUP, "force", sc->n, KERGS_MAXCOMP, &sc->force));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  PetscFunctionReturn(0);
}

static PetscBool IsId(PetscReal v) { return (PetscBool)(v >= 0 && v == PetscFloorReal(v) && v < (PetscReal)PETSC_MAX_INT); }

/* Record k names a grain (a non-negative integer id) with a grain of larger id (the warm start's key) or with a wall of
   the file's list, by a finite force whose normal part pushes. */
static PetscBool RecordValid(const SampleContacts *sc, PetscInt k)
{
  PetscBool ok = (PetscBool)(IsId(sc->ida[k]) && IsId(sc->idb[k]) &&
                             ((sc->kind[k] == 0.0 && sc->idb[k] > sc->ida[k]) || (sc->kind[k] == 1.0 && sc->idb[k] < sc->nwalls)));

  for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) ok = (PetscBool)(ok && !PetscIsInfOrNanReal(sc->force[KERGS_MAXCOMP * k + j]));
  ok = (PetscBool)(ok && sc->force[KERGS_MAXCOMP * k] >= 0); /* contacts push: a normal force is never a pull */
  return ok;
}

/* The file's contacts of the grains owned here, as key-only contacts (b = -1) carrying the impulse force * dt, sorted
   by key. count[0]: those kept; count[1]: those with a wall the scene does not have, left out; count[2]: records of a
   pair given before. Every record is checked (every rank holds them all, so all stop on the same one). */
static PetscErrorCode SampleContactsOwned(const char path[], KergsScene scene, const SampleContacts *sc, KergsContact **c,
                                          PetscInt count[3])
{
  KergsDisks       D;
  KergsGrainIndex *table;
  PetscInt         nhit = 0;
  PetscReal        dt;
  MPI_Comm         comm;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(KergsSceneGetTimeStep(scene, &dt, NULL));
  PetscCall(KergsSceneGetGrainIndex(scene, D.nowned, &table));
  for (PetscInt k = 0; k < sc->n; k++) {
    PetscCheck(RecordValid(sc, k), comm, PETSC_ERR_FILE_UNEXPECTED,
               "Sample file %s: contact %" PetscInt_FMT " of %s is not a contact of a grain with a grain of larger id or a named wall, "
               "with a finite force that pushes",
               path, k, KERGS_CONTACTS_GROUP);
    nhit += KergsGrainIndexFind(table, D.nowned, (PetscInt)sc->ida[k]) >= 0;
  }
  PetscCall(PetscMalloc1(nhit + 1, c)); /* this rank's share, not the whole file's */
  count[0] = count[1] = count[2] = 0;
  for (PetscInt k = 0; k < sc->n; k++) {
    const PetscInt wall = sc->kind[k] != 0.0, a = KergsGrainIndexFind(table, D.nowned, (PetscInt)sc->ida[k]);
    KergsContact  *ck = &(*c)[count[0]];

    if (a < 0) continue;
    if (wall && sc->wall[(PetscInt)sc->idb[k]] < 0) {
      count[1]++;
      continue;
    }
    PetscCall(PetscMemzero(ck, sizeof(*ck)));
    ck->kind = wall ? KERGS_CONTACT_DISK_WALL : KERGS_CONTACT_DISK_DISK;
    ck->a    = a;
    ck->b    = -1;
    ck->idb  = wall ? sc->wall[(PetscInt)sc->idb[k]] : (PetscInt)sc->idb[k];
    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) ck->r[j] = sc->force[KERGS_MAXCOMP * k + j] * dt;
    count[0]++;
  }
  qsort(*c, (size_t)count[0], sizeof(KergsContact), CompareKeys);
  for (PetscInt k = 1; k < count[0]; k++) count[2] += KERGS_COMPARE_KEYS(&(*c)[k - 1], &(*c)[k]) == 0;
  PetscCall(PetscFree(table));
  PetscFunctionReturn(0);
}

/* Whether the sample file holds /sample/contacts, checked to be what SampleContactsLoad reads before PETSc's viewer
   reads it (an array where one value was expected crashed the viewer's attribute reader); the viewer opened on the file
   when it does. */
static PetscErrorCode SampleContactsOpen(MPI_Comm comm, const char path[], PetscViewer *viewer, PetscBool *has)
{
  const KergsH5Item items[] = {
      {KERGS_H5_ATTR_INT, KERGS_CONTACTS_GROUP, "ncontacts", 0, 0}, {KERGS_H5_ATTR_STRING, KERGS_CONTACTS_GROUP, "walls", 0, 0},
      {KERGS_H5_DATASET, KERGS_CONTACTS_GROUP, "a_id", -1, 1},      {KERGS_H5_DATASET, KERGS_CONTACTS_GROUP, "kind", -1, 1},
      {KERGS_H5_DATASET, KERGS_CONTACTS_GROUP, "b_id", -1, 1},      {KERGS_H5_DATASET, KERGS_CONTACTS_GROUP, "force", -1, KERGS_MAXCOMP}};
  PetscBool group, other;

  PetscFunctionBeginUser;
  PetscCall(KergsH5CheckFile(comm, path, "Sample file", KERGS_SAMPLE_FORMAT, "kergs sample"));
  PetscCall(PetscViewerHDF5Open(comm, path, FILE_MODE_READ, viewer));
  PetscCall(PetscViewerHDF5HasGroup(*viewer, KERGS_CONTACTS_GROUP, &group));
  PetscCall(PetscViewerHDF5HasDataset(*viewer, KERGS_CONTACTS_GROUP, &other));
  PetscCall(PetscViewerDestroy(viewer));
  PetscCheck(!other, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: %s is a dataset, not the group of contact forces", path,
             KERGS_CONTACTS_GROUP);
  *has = group;
  if (!group) PetscFunctionReturn(0);
  PetscCall(KergsH5CheckItems(comm, path, "Sample file", (PetscInt)PETSC_STATIC_ARRAY_LENGTH(items), items));
  PetscCall(PetscViewerHDF5Open(comm, path, FILE_MODE_READ, viewer));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSampleReadForces(KergsScene scene, KergsContacts contacts, PetscInt *nforces)
{
  const char    *path;
  PetscViewer    viewer;
  PetscBool      has      = PETSC_FALSE;
  PetscInt       count[3] = {0, 0, 0}, total[3];
  SampleContacts sc       = {0};
  KergsContact  *c        = NULL;
  MPI_Comm       comm;
  PetscErrorCode ierr;

  PetscFunctionBeginUser;
  if (nforces) *nforces = 0;
  PetscCall(KergsSceneGetSamplePath(scene, &path));
  if (!path[0]) PetscFunctionReturn(0);
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(SampleContactsOpen(comm, path, &viewer, &has));
  if (!has) {
    PetscCall(PetscInfo(NULL, "Sample file %s records no contact forces: the first step starts from zero impulses\n", path));
    PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
    PetscFunctionReturn(0);
  }
  PetscCall(KergsErrorsHoldBegin());
  ierr = SampleContactsLoad(viewer, path, scene, &sc);
  PetscCall(KergsErrorsHoldEnd());
  PetscCall(PetscViewerDestroy(&viewer));
  if (ierr) PetscCall(SampleContactsFree(&sc));
  PetscCall(KergsErrorsRaiseHeld(comm, ierr, "Sample file", path));
  PetscCall(SampleContactsOwned(path, scene, &sc, &c, count));
  PetscCall(SampleContactsFree(&sc));
  PetscCallMPI(MPI_Allreduce(count, total, 3, MPIU_INT, MPI_SUM, comm));
  PetscCheck(total[2] == 0, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: %" PetscInt_FMT " of its contacts repeat a pair given before",
             path, total[2]);
  PetscCheck(total[0] + total[1] == sc.n, comm, PETSC_ERR_FILE_UNEXPECTED,
             "Sample file %s: %" PetscInt_FMT " of its %" PetscInt_FMT " contacts belong to no grain of the sample", path,
             sc.n - total[0] - total[1], sc.n);
  if (contacts && total[1])
    PetscCall(PetscPrintf(
        comm, "kergs: %" PetscInt_FMT " contact forces of sample file %s are with walls this scene does not have: they start from zero\n",
        total[1], path));
  if (contacts)
    PetscCall(PetscInfo(NULL, "Sample file %s: %" PetscInt_FMT " contact forces as the first step's warm start\n", path, total[0]));
  if (contacts) PetscCall(KergsContactsRestore(contacts, count[0], c));
  if (nforces) *nforces = total[0];
  PetscCall(PetscFree(c));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
