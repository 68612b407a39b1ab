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

#define KERGS_SAMPLE_GROUP   "/sample"
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

/* The walls' names joined by commas, in wall order: the contacts name their wall by its index in this list. */
static PetscErrorCode JoinWallNames(KergsScene scene, char **joined)
{
  PetscInt         nwalls;
  const KergsWall *walls;
  size_t           len = 1;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetWalls(scene, &nwalls, &walls));
  for (PetscInt w = 0; w < nwalls; w++) len += strlen(walls[w].name) + 1;
  PetscCall(PetscCalloc1(len, joined));
  for (PetscInt w = 0; w < nwalls; w++) {
    if (w) PetscCall(PetscStrlcat(*joined, ",", len));
    PetscCall(PetscStrlcat(*joined, walls[w].name, len));
  }
  PetscFunctionReturn(0);
}

/* /sample/contacts: every contact that carries a force at the end of the run, keyed as the warm start keys them (grain
   id of a, kind, grain id or wall index of b), with its force r / dt in the contact frame, so that a run of another
   time step reads the same forces. */
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
    PetscBool loaded = PETSC_FALSE;

    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) loaded = (PetscBool)(loaded || c[i].r[j] != 0.0);
    if (!loaded) continue;
    ida[k]  = D.id[c[i].a];
    kind[k] = c[i].kind == KERGS_CONTACT_DISK_WALL ? 1 : 0;
    idb[k]  = c[i].idb;
    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) force[KERGS_MAXCOMP * k + j] = c[i].r[j] / dt;
    k++;
  }
  PetscCallMPI(MPI_Allreduce(&k, &total, 1, MPIU_INT, MPI_SUM, comm));
  PetscCall(JoinWallNames(scene, &walls));
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
  PetscReal   sctime;
  char        tmp[PETSC_MAX_PATH_LEN];
  PetscViewer viewer;
  MPI_Comm    comm;
  PetscInt    n, nl;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(KergsSceneGetStep(scene, NULL, &sctime, NULL));
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
  PetscCall(PetscViewerHDF5WriteAttribute(viewer, "/", "kergs_format", PETSC_STRING, "kergs sample 1"));
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
  if (contacts) PetscCall(SampleWriteContacts(viewer, scene, contacts));
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
  PetscBool        has;
  PetscErrorCode   ierr;
  MPI_Comm         comm;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetWalls(scene, &nwalls, &walls));
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(PetscViewerHDF5HasAttribute(viewer, KERGS_CONTACTS_GROUP, "walls", &has));
  PetscCheck(has, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s has no attribute walls on %s", path, KERGS_CONTACTS_GROUP);
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = PetscViewerHDF5ReadAttribute(viewer, KERGS_CONTACTS_GROUP, "walls", PETSC_STRING, NULL, &names);
  PetscCall(PetscPopErrorHandler());
  PetscCheck(!ierr, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: the attribute walls of %s is not a fixed-length string of wall names",
             path, KERGS_CONTACTS_GROUP);
  PetscCall(PetscStrToArray(names, ',', &argc, &list));
  PetscCall(PetscMalloc1(argc + 1, map));
  for (int k = 0; k < argc; k++) {
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

static int CompareIdLocal(const void *x, const void *y)
{
  const PetscInt *p = (const PetscInt *)x, *q = (const PetscInt *)y;
  return p[0] < q[0] ? -1 : (p[0] > q[0] ? 1 : 0);
}

static int CompareKeys(const void *p, const void *q) { return KERGS_COMPARE_KEYS((const KergsContact *)p, (const KergsContact *)q); }

/* The file's contacts of the grains owned here, as key-only contacts (b = -1) carrying the impulse force * dt, sorted
   by key; a contact with a wall the scene does not have is left out (*nwall counts them), and *nrepeated counts the
   records of a pair already given. */
static PetscErrorCode SampleContactsOwned(const char path[], KergsScene scene, PetscInt nfile, const PetscReal *ida, const PetscReal *kind,
                                          const PetscReal *idb, const PetscReal *force, PetscInt nmap, const PetscInt *map, PetscInt *n,
                                          KergsContact **c, PetscInt *nwall, PetscInt *nrepeated)
{
  KergsDisks D;
  PetscInt  *table; /* pairs (grain id, local index) of the owned grains, sorted by id */
  PetscReal  dt;
  MPI_Comm   comm;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(scene, &D));
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(KergsSceneGetTimeStep(scene, &dt, NULL));
  PetscCall(PetscMalloc1(2 * D.nowned + 2, &table));
  for (PetscInt i = 0; i < D.nowned; i++) {
    table[2 * i]     = D.id[i];
    table[2 * i + 1] = i;
  }
  qsort(table, (size_t)D.nowned, 2 * sizeof(PetscInt), CompareIdLocal);
  PetscCall(PetscMalloc1(nfile + 1, c));
  *n     = 0;
  *nwall = 0;
  for (PetscInt k = 0; k < nfile; k++) {
    const PetscInt  wall = kind[k] != 0.0, key[2] = {(PetscInt)ida[k], 0};
    const PetscInt *hit;
    KergsContact   *ck = &(*c)[*n];

    PetscCheck(!PetscIsInfOrNanReal(force[KERGS_MAXCOMP * k]) && !PetscIsInfOrNanReal(force[KERGS_MAXCOMP * k + 1]) &&
                 (kind[k] == 0.0 || kind[k] == 1.0) && ida[k] >= 0 && idb[k] >= 0 && (!wall || idb[k] < nmap),
               comm, PETSC_ERR_FILE_UNEXPECTED, /* every rank holds every record: all stop here together */
               "Sample file %s: contact %" PetscInt_FMT " of %s is not a contact of a grain with a grain or a named wall with a finite force",
               path, k, KERGS_CONTACTS_GROUP);
    hit = (const PetscInt *)bsearch(key, table, (size_t)D.nowned, 2 * sizeof(PetscInt), CompareIdLocal);
    if (!hit) continue;
    if (wall && map[(PetscInt)idb[k]] < 0) {
      (*nwall)++;
      continue;
    }
    PetscCall(PetscMemzero(ck, sizeof(*ck)));
    ck->kind = wall ? KERGS_CONTACT_DISK_WALL : KERGS_CONTACT_DISK_DISK;
    ck->a    = hit[1];
    ck->b    = -1;
    ck->idb  = wall ? map[(PetscInt)idb[k]] : (PetscInt)idb[k];
    for (PetscInt j = 0; j < KERGS_MAXCOMP; j++) ck->r[j] = force[KERGS_MAXCOMP * k + j] * dt;
    (*n)++;
  }
  qsort(*c, (size_t)*n, sizeof(KergsContact), CompareKeys);
  *nrepeated = 0;
  for (PetscInt k = 1; k < *n; k++) *nrepeated += KERGS_COMPARE_KEYS(&(*c)[k - 1], &(*c)[k]) == 0;
  PetscCall(PetscFree(table));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSampleReadImpulses(KergsScene scene, KergsContacts contacts)
{
  const char   *path;
  PetscViewer   viewer;
  PetscBool     has;
  PetscInt      nfile = 0, nmap = 0, *map, n = 0, nwall = 0, nrepeated = 0, sums[3], totals[3];
  PetscReal    *ida, *kind, *idb, *force;
  KergsContact *c;
  MPI_Comm      comm;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetSamplePath(scene, &path));
  if (!path[0]) PetscFunctionReturn(0);
  PetscCall(KergsSceneGetComm(scene, &comm));
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(KergsH5CheckFile(comm, path, "Sample file", NULL, NULL));
  PetscCall(PetscViewerHDF5Open(comm, path, FILE_MODE_READ, &viewer));
  PetscCall(PetscViewerHDF5HasGroup(viewer, KERGS_CONTACTS_GROUP, &has));
  if (!has) {
    PetscCall(PetscInfo(NULL, "Sample file %s records no contact forces: the first step starts from zero impulses\n", path));
    PetscCall(PetscViewerDestroy(&viewer));
    PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
    PetscFunctionReturn(0);
  }
  PetscCall(PetscViewerHDF5HasAttribute(viewer, KERGS_CONTACTS_GROUP, "ncontacts", &has));
  PetscCheck(has, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s has no attribute ncontacts on %s", path, KERGS_CONTACTS_GROUP);
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, KERGS_CONTACTS_GROUP, "ncontacts", PETSC_INT, NULL, &nfile));
  PetscCheck(nfile >= 0, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: %s has %" PetscInt_FMT " contacts", path, KERGS_CONTACTS_GROUP,
             nfile);
  PetscCall(MapWalls(viewer, path, scene, &nmap, &map));
  PetscCall(PetscViewerHDF5PushGroup(viewer, KERGS_CONTACTS_GROUP));
  PetscCall(KergsLoadAllBlocks(viewer, comm, path, KERGS_CONTACTS_GROUP, "a_id", nfile, 1, &ida));
  PetscCall(KergsLoadAllBlocks(viewer, comm, path, KERGS_CONTACTS_GROUP, "kind", nfile, 1, &kind));
  PetscCall(KergsLoadAllBlocks(viewer, comm, path, KERGS_CONTACTS_GROUP, "b_id", nfile, 1, &idb));
  PetscCall(KergsLoadAllBlocks(viewer, comm, path, KERGS_CONTACTS_GROUP, "force", nfile, KERGS_MAXCOMP, &force));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  PetscCall(PetscViewerDestroy(&viewer));
  PetscCall(SampleContactsOwned(path, scene, nfile, ida, kind, idb, force, nmap, map, &n, &c, &nwall, &nrepeated));
  sums[0] = n;
  sums[1] = nwall;
  sums[2] = nrepeated;
  PetscCallMPI(MPI_Allreduce(sums, totals, 3, MPIU_INT, MPI_SUM, comm));
  PetscCheck(totals[2] == 0, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: %" PetscInt_FMT " of its contacts repeat a pair given before",
             path, totals[2]);
  PetscCheck(totals[0] + totals[1] == nfile, comm, PETSC_ERR_FILE_UNEXPECTED,
             "Sample file %s: %" PetscInt_FMT " of its %" PetscInt_FMT " contacts belong to no grain of the sample", path,
             nfile - totals[0] - totals[1], nfile);
  if (contacts && totals[1])
    PetscCall(PetscInfo(NULL, "Sample file %s: %" PetscInt_FMT " contacts with walls this scene does not have start from zero\n", path, totals[1]));
  if (contacts) PetscCall(PetscInfo(NULL, "Sample file %s: %" PetscInt_FMT " contact forces as the first step's warm start\n", path, totals[0]));
  if (contacts) PetscCall(KergsContactsRestore(contacts, n, c));
  PetscCall(PetscFree(c));
  PetscCall(PetscFree(map));
  PetscCall(PetscFree(ida));
  PetscCall(PetscFree(kind));
  PetscCall(PetscFree(idb));
  PetscCall(PetscFree(force));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
