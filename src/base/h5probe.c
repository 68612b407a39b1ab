/* kergs HDF5 probes: a quick, quiet look at a file before PETSc's viewer or libfclib opens it
   (include/kergs/private/h5probe.h). */
#include <kergs/private/h5probe.h>
#include <string.h>

void KergsH5QuietBegin(KergsH5Quiet *q)
{
  q->handler = NULL;
  q->data    = NULL;
  q->saved   = (PetscBool)(H5Eget_auto2(H5E_DEFAULT, &q->handler, &q->data) >= 0);
  if (q->saved) (void)H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
}

void KergsH5QuietEnd(const KergsH5Quiet *q)
{
  if (q->saved) (void)H5Eset_auto2(H5E_DEFAULT, q->handler, q->data);
}

PetscBool KergsH5HasFormat(hid_t file, const char format[])
{
  char      value[64] = "";
  hid_t     attr      = H5Aopen_by_name(file, "/", "kergs_format", H5P_DEFAULT, H5P_DEFAULT);
  hid_t     type      = H5Tcopy(H5T_C_S1);
  PetscBool has;

  (void)H5Tset_size(type, sizeof(value) - 1);
  has = (PetscBool)(attr >= 0 && H5Aread(attr, type, value) >= 0 && !strcmp(value, format)); /* exactly: "... 10" is not "... 1" */
  (void)H5Tclose(type);
  if (attr >= 0) (void)H5Aclose(attr);
  return has;
}

/* Rank 0's verdict on path (msg empty: good). */
static PetscErrorCode ProbeFile(const char path[], const char what[], const char format[], const char kind[], char msg[], size_t len)
{
  PetscBool    readable;
  KergsH5Quiet quiet;
  hid_t        file;

  PetscFunctionBeginUser;
  PetscCall(PetscTestFile(path, 'r', &readable));
  if (!readable) {
    PetscCall(PetscSNPrintf(msg, len, "%s %s does not exist or is not readable", what, path));
    PetscFunctionReturn(0);
  }
  KergsH5QuietBegin(&quiet);
  file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
  if (file < 0)
    PetscCall(PetscSNPrintf(msg, len, "%s %s cannot be opened as HDF5: not an HDF5 file, or truncated or corrupt", what, path));
  else if (format && !KergsH5HasFormat(file, format))
    PetscCall(PetscSNPrintf(msg, len, "File %s is not a %s (root attribute kergs_format is not \"%s\")", path, kind, format));
  if (file >= 0 && H5Fclose(file) < 0 && !msg[0])
    PetscCall(PetscSNPrintf(msg, len, "%s %s: HDF5 cannot close it after opening", what, path));
  KergsH5QuietEnd(&quiet);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsH5CheckFile(MPI_Comm comm, const char path[], const char what[], const char format[], const char kind[])
{
  char        msg[PETSC_MAX_PATH_LEN + 256] = "";
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) PetscCall(ProbeFile(path, what, format, kind, msg, sizeof(msg)));
  PetscCallMPI(MPI_Bcast(msg, (int)sizeof(msg), MPI_CHAR, 0, comm));
  PetscCheck(msg[0] == 0, comm, PETSC_ERR_FILE_OPEN, "%s", msg);
  PetscFunctionReturn(0);
}
