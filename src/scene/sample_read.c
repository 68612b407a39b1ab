/* kergs scene, disk source "file": a sample written by an earlier run (src/io/sample.c; layout in docs/results.md)
   replaces the scene's disks. The file is checked to be a readable HDF5 file before PETSc opens it, then every size
   and value (finite numbers, positive radii, existing materials, grain ids non-negative and distinct), so that a bad
   file gives an error that names it and what is wrong in it, never a crash. */
#include <kergs/private/sceneimpl.h>
#include <kergs/private/h5probe.h>
#include <petscviewerhdf5.h>
#include <petsclayouthdf5.h>

#define KERGS_SAMPLE_GROUP "/sample"

/* A packing as read from the file, replicated on every rank. */
typedef struct {
  PetscInt   n;
  PetscReal  time;
  PetscReal *x, *v, *rot, *omega, *radius, *material, *id;
} SampleData;

static PetscErrorCode SampleDataFree(SampleData *s)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree(s->x));
  PetscCall(PetscFree(s->v));
  PetscCall(PetscFree(s->rot));
  PetscCall(PetscFree(s->omega));
  PetscCall(PetscFree(s->radius));
  PetscCall(PetscFree(s->material));
  PetscCall(PetscFree(s->id));
  PetscFunctionReturn(0);
}

/* Load /sample/<name> (n blocks of bs reals) into a newly allocated replicated array. */
static PetscErrorCode SampleLoadField(PetscViewer viewer, MPI_Comm comm, const char path[], const char name[], PetscInt n, PetscInt bs,
                                      PetscReal **all)
{
  PetscBool          has;
  PetscInt           fbs, fN;
  PetscErrorCode     ierr, anyerr;
  Vec                vec, seq;
  VecScatter         toall;
  const PetscScalar *a;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5HasDataset(viewer, name, &has));
  PetscCheck(has, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s has no dataset %s/%s", path, KERGS_SAMPLE_GROUP, name);
  PetscCall(PetscViewerHDF5ReadSizes(viewer, name, &fbs, &fN));
  PetscCheck(fN == n * bs && (fbs == bs || n == 0), comm, PETSC_ERR_FILE_UNEXPECTED,
             "Sample file %s: dataset %s/%s holds %" PetscInt_FMT " values in blocks of %" PetscInt_FMT ", expected ndisks x %" PetscInt_FMT
             " = %" PetscInt_FMT,
             path, KERGS_SAMPLE_GROUP, name, fN, fbs, bs, n * bs);
  PetscCall(VecCreate(comm, &vec));
  PetscCall(VecSetSizes(vec, PETSC_DECIDE, n * bs));
  PetscCall(VecSetBlockSize(vec, bs));
  PetscCall(VecSetType(vec, VECMPI));
  PetscCall(PetscObjectSetName((PetscObject)vec, name));
  /* A read failure inside HDF5 becomes an error that names the file, on every rank. */
  PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
  ierr = VecLoad(vec, viewer);
  PetscCall(PetscPopErrorHandler());
  PetscCall(MPIU_Allreduce(&ierr, &anyerr, 1, MPI_INT, MPI_MAX, comm));
  PetscCheck(!anyerr, comm, PETSC_ERR_FILE_READ, "Cannot read dataset %s/%s of sample file %s: corrupt or truncated file",
             KERGS_SAMPLE_GROUP, name, path);
  PetscCall(VecScatterCreateToAll(vec, &toall, &seq));
  PetscCall(VecScatterBegin(toall, vec, seq, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(toall, vec, seq, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(PetscMalloc1(n * bs, all));
  PetscCall(VecGetArrayRead(seq, &a));
  for (PetscInt i = 0; i < n * bs; i++) (*all)[i] = PetscRealPart(a[i]);
  PetscCall(VecRestoreArrayRead(seq, &a));
  PetscCall(VecScatterDestroy(&toall));
  PetscCall(VecDestroy(&seq));
  PetscCall(VecDestroy(&vec));
  PetscFunctionReturn(0);
}

static PetscErrorCode SampleLoad(PetscViewer viewer, MPI_Comm comm, const char path[], SampleData *s)
{
  PetscBool has;
  PetscInt  dim;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5HasGroup(viewer, KERGS_SAMPLE_GROUP, &has));
  PetscCheck(has, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s has no group %s", path, KERGS_SAMPLE_GROUP);
  PetscCall(PetscViewerHDF5PushGroup(viewer, KERGS_SAMPLE_GROUP));
  PetscCall(PetscViewerHDF5HasAttribute(viewer, NULL, "dim", &has));
  PetscCheck(has, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s has no attribute dim on %s", path, KERGS_SAMPLE_GROUP);
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, NULL, "dim", PETSC_INT, NULL, &dim));
  PetscCheck(dim == KERGS_DIM, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s is of dimension %" PetscInt_FMT ", kergs computes in %d",
             path, dim, KERGS_DIM);
  PetscCall(PetscViewerHDF5HasAttribute(viewer, NULL, "ndisks", &has));
  PetscCheck(has, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s has no attribute ndisks on %s", path, KERGS_SAMPLE_GROUP);
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, NULL, "ndisks", PETSC_INT, NULL, &s->n));
  PetscCheck(s->n >= 1, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: ndisks = %" PetscInt_FMT ": a sample holds at least one grain",
             path, s->n);
  PetscCheck(s->n <= KERGS_MAX_DISKS, comm, PETSC_ERR_FILE_UNEXPECTED,
             "Sample file %s: ndisks = %" PetscInt_FMT " is more than this build holds (%" PetscInt_FMT ", 32-bit PetscInt)", path, s->n,
             (PetscInt)KERGS_MAX_DISKS);
  PetscCall(PetscViewerHDF5HasAttribute(viewer, NULL, "time", &has));
  PetscCheck(has, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s has no attribute time on %s", path, KERGS_SAMPLE_GROUP);
  PetscCall(PetscViewerHDF5ReadAttribute(viewer, NULL, "time", PETSC_REAL, NULL, &s->time));
  PetscCall(SampleLoadField(viewer, comm, path, "x", s->n, KERGS_DIM, &s->x));
  PetscCall(SampleLoadField(viewer, comm, path, "v", s->n, KERGS_DIM, &s->v));
  PetscCall(SampleLoadField(viewer, comm, path, "rot", s->n, KERGS_NROT, &s->rot));
  PetscCall(SampleLoadField(viewer, comm, path, "omega", s->n, KERGS_NROT, &s->omega));
  PetscCall(SampleLoadField(viewer, comm, path, "radius", s->n, 1, &s->radius));
  PetscCall(SampleLoadField(viewer, comm, path, "material", s->n, 1, &s->material));
  PetscCall(SampleLoadField(viewer, comm, path, "id", s->n, 1, &s->id));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  PetscFunctionReturn(0);
}

/* First non-finite entry of a (n blocks of bs), as a disk index, or -1. */
static PetscInt FirstNonFinite(const PetscReal *a, PetscInt n, PetscInt bs)
{
  for (PetscInt i = 0; i < n * bs; i++)
    if (PetscIsInfOrNanReal(a[i])) return i / bs;
  return -1;
}

/* Grain ids identify grains (contact persistence, ownership, outputs): two disks with one id would silently lose
   contacts. Names the first repeated id and the two disks that carry it. */
static PetscErrorCode SampleCheckDistinctIds(MPI_Comm comm, const char path[], const SampleData *s)
{
  PetscInt *ids, *order;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(s->n + 1, &ids, s->n + 1, &order));
  for (PetscInt i = 0; i < s->n; i++) {
    ids[i]   = (PetscInt)s->id[i];
    order[i] = i;
  }
  PetscCall(PetscSortIntWithArray(s->n, ids, order));
  for (PetscInt k = 1; k < s->n; k++) {
    const PetscInt id = ids[k], first = PetscMin(order[k - 1], order[k]), second = PetscMax(order[k - 1], order[k]);
    if (ids[k - 1] != id) continue;
    PetscCall(PetscFree2(ids, order));
    SETERRQ(comm, PETSC_ERR_FILE_UNEXPECTED,
            "Sample file %s: disks %" PetscInt_FMT " and %" PetscInt_FMT " have the same grain id %" PetscInt_FMT "; ids must be distinct",
            path, first, second, id);
  }
  PetscCall(PetscFree2(ids, order));
  PetscFunctionReturn(0);
}

/* Every value finite, radii positive, materials existing in the scene, ids non-negative integers. */
static PetscErrorCode SampleValidate(KergsScene scene, const char path[], const SampleData *s)
{
  const struct {
    const char      *name;
    const PetscReal *a;
    PetscInt         bs;
  } fields[] = {{"x", s->x, KERGS_DIM},
                {"v", s->v, KERGS_DIM},
                {"rot", s->rot, KERGS_NROT},
                {"omega", s->omega, KERGS_NROT},
                {"radius", s->radius, 1},
                {"material", s->material, 1},
                {"id", s->id, 1}};

  PetscFunctionBeginUser;
  PetscCheck(!PetscIsInfOrNanReal(s->time), scene->comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: time is not finite", path);
  for (size_t f = 0; f < sizeof(fields) / sizeof(fields[0]); f++) {
    PetscInt bad = FirstNonFinite(fields[f].a, s->n, fields[f].bs);
    PetscCheck(bad < 0, scene->comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: %s of disk %" PetscInt_FMT " is not finite", path,
               fields[f].name, bad);
  }
  for (PetscInt i = 0; i < s->n; i++) {
    const PetscReal m = s->material[i], id = s->id[i];
    PetscCheck(s->radius[i] > 0, scene->comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s: disk %" PetscInt_FMT " has radius %g <= 0", path,
               i, (double)s->radius[i]);
    PetscCheck(m == PetscFloorReal(m) && m >= 0 && m < scene->nmaterials, scene->comm, PETSC_ERR_FILE_UNEXPECTED,
               "Sample file %s: disk %" PetscInt_FMT " has material %g, the scene has materials 0..%" PetscInt_FMT, path, i, (double)m,
               scene->nmaterials - 1);
    PetscCheck(id == PetscFloorReal(id) && id >= 0 && id < (PetscReal)PETSC_MAX_INT, scene->comm, PETSC_ERR_FILE_UNEXPECTED,
               "Sample file %s: disk %" PetscInt_FMT " has id %g, not a non-negative integer", path, i, (double)id);
  }
  PetscCall(SampleCheckDistinctIds(scene->comm, path, s));
  PetscFunctionReturn(0);
}

/* Hand the disks to the scene (KergsSceneSetDisks allocates and computes masses), then the state it
   does not take: orientations, angular velocities, ids and the clock. */
static PetscErrorCode SampleApply(KergsScene scene, const SampleData *s)
{
  PetscInt *material;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(s->n, &material));
  for (PetscInt i = 0; i < s->n; i++) material[i] = (PetscInt)s->material[i];
  PetscCall(KergsSceneSetDisks(scene, s->n, s->x, s->radius, material, s->v));
  PetscCall(PetscFree(material));
  PetscCheck(scene->ndisks == s->n, scene->comm, PETSC_ERR_PLIB, "KergsSceneSetDisks() left %" PetscInt_FMT " disks, not %" PetscInt_FMT,
             scene->ndisks, s->n);
  /* every rank read the whole file; it keeps the state of its owned slice */
  for (PetscInt i = 0; i < scene->nowned; i++) {
    const PetscInt g = scene->dstart + i;
    for (PetscInt d = 0; d < KERGS_NROT; d++) {
      scene->rot[KERGS_NROT * i + d]   = s->rot[KERGS_NROT * g + d];
      scene->omega[KERGS_NROT * i + d] = s->omega[KERGS_NROT * g + d];
    }
    scene->id[i] = (PetscInt)s->id[g];
  }
  /* The sample is the initial state of a new run, whose clock starts at 0 as its step count starts at 1, so that a
     wall's velocity program is written in the run's own time. s->time, the writing run's, is only checked. */
  scene->time = 0.0;
  PetscFunctionReturn(0);
}

/* A sample file opened for reading; PETSc's viewer is only ever given a good file. */
static PetscErrorCode SampleOpen(MPI_Comm comm, const char path[], PetscViewer *viewer)
{
  PetscFunctionBeginUser;
  PetscCheck(path && path[0], comm, PETSC_ERR_ARG_WRONG, "Sample file name is empty");
  PetscCall(KergsH5CheckFile(comm, path, "Sample file", KERGS_SAMPLE_FORMAT, "kergs sample"));
  PetscCall(PetscViewerHDF5Open(comm, path, FILE_MODE_READ, viewer));
  PetscFunctionReturn(0);
}

/* The box is optional in a sample (a run without -box records none), so its absence gets its own message. */
static PetscErrorCode SampleLoadBox(PetscViewer viewer, MPI_Comm comm, const char path[], PetscReal box[4])
{
  PetscBool  has;
  PetscReal *b;

  PetscFunctionBeginUser;
  PetscCall(PetscViewerHDF5HasGroup(viewer, KERGS_SAMPLE_GROUP, &has));
  PetscCheck(has, comm, PETSC_ERR_FILE_UNEXPECTED, "Sample file %s has no group %s", path, KERGS_SAMPLE_GROUP);
  PetscCall(PetscViewerHDF5PushGroup(viewer, KERGS_SAMPLE_GROUP));
  PetscCall(PetscViewerHDF5HasDataset(viewer, "box", &has));
  PetscCheck(
      has, comm, PETSC_ERR_FILE_UNEXPECTED,
      "Sample file %s records no box (%s/box): the run that wrote it had no -box walls; give -box x0,y0,x1,y1 instead of -box_from_sample",
      path, KERGS_SAMPLE_GROUP);
  PetscCall(SampleLoadField(viewer, comm, path, "box", 1, 4, &b));
  PetscCall(PetscViewerHDF5PopGroup(viewer));
  for (PetscInt k = 0; k < 4; k++) box[k] = b[k];
  PetscCall(PetscFree(b));
  PetscCheck(FirstNonFinite(box, 1, 4) < 0 && box[2] > box[0] && box[3] > box[1], comm, PETSC_ERR_FILE_UNEXPECTED,
             "Sample file %s: its box %g,%g,%g,%g is not x0 < x1, y0 < y1", path, (double)box[0], (double)box[1], (double)box[2],
             (double)box[3]);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSampleReadBox(MPI_Comm comm, const char path[], PetscReal box[4])
{
  PetscViewer    viewer;
  PetscErrorCode ierr;

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(SampleOpen(comm, path, &viewer));
  PetscCall(KergsErrorsHoldBegin());
  ierr = SampleLoadBox(viewer, comm, path, box);
  PetscCall(KergsErrorsHoldEnd());
  PetscCall(PetscViewerDestroy(&viewer));
  PetscCall(KergsErrorsRaiseHeld(comm, ierr, "Sample file", path));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSampleRead(KergsScene scene, const char path[])
{
  MPI_Comm       comm = scene->comm;
  PetscViewer    viewer;
  SampleData     s = {0};
  PetscErrorCode ierr;

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscLogEventBegin(KERGS_IO, 0, 0, 0, 0));
  PetscCall(SampleOpen(comm, path, &viewer));
  PetscCall(KergsErrorsHoldBegin());
  ierr = SampleLoad(viewer, comm, path, &s);
  PetscCall(KergsErrorsHoldEnd());
  PetscCall(PetscViewerDestroy(&viewer));
  if (ierr) PetscCall(SampleDataFree(&s));
  PetscCall(KergsErrorsRaiseHeld(comm, ierr, "Sample file", path));
  ierr = SampleValidate(scene, path, &s);
  if (!ierr) ierr = SampleApply(scene, &s);
  PetscCall(SampleDataFree(&s));
  PetscCall(ierr);
  PetscCall(PetscStrncpy(scene->sample_path, path, sizeof(scene->sample_path)));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneGetSamplePath(KergsScene scene, const char **path)
{
  PetscFunctionBeginUser;
  *path = scene->sample_path;
  PetscFunctionReturn(0);
}
