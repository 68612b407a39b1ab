/* kergs sample: a packing of disks saved by one run, for another to start from (layout in docs/results.md; read by
   the scene's disk source "file", src/scene/sample_read.c). Written through PetscViewerHDF5 to "<path>.tmp" and
   renamed when complete. */
#include <kergs/sample.h>
#include <kergs/results.h>
#include <petscviewerhdf5.h>
#include <stdio.h>

#define KERGS_SAMPLE_GROUP "/sample"

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

PetscErrorCode KergsSampleWrite(KergsScene scene, const char path[])
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
  PetscCall(PetscViewerDestroy(&viewer));
  PetscCall(KergsFileCommit(comm, tmp, path));
  PetscCall(PetscLogEventEnd(KERGS_IO, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}
