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

/* An attribute holds one value of the given class (a string of fixed length): empty msg when it does; an integer's value
   in *value. */
static void ProbeAttribute(hid_t file, const KergsH5Item *it, long long *value, char msg[], size_t len)
{
  const char *want = it->kind == KERGS_H5_ATTR_INT ? "a single integer" : "a single fixed-length string";
  hid_t       attr = H5Aexists_by_name(file, it->object, it->name, H5P_DEFAULT) > 0
                         ? H5Aopen_by_name(file, it->object, it->name, H5P_DEFAULT, H5P_DEFAULT)
                         : -1;
  hid_t       type = attr >= 0 ? H5Aget_type(attr) : -1, space = attr >= 0 ? H5Aget_space(attr) : -1;
  H5T_class_t cls = type >= 0 ? H5Tget_class(type) : H5T_NO_CLASS;
  PetscBool   ok;

  ok = (PetscBool)(space >= 0 && H5Sget_simple_extent_npoints(space) == 1 &&
                   (it->kind == KERGS_H5_ATTR_INT ? cls == H5T_INTEGER : cls == H5T_STRING && H5Tis_variable_str(type) == 0));
  if (attr < 0)
    (void)PetscSNPrintf(msg, len, "has no attribute %s on %s", it->name, it->object);
  else if (!ok)
    (void)PetscSNPrintf(msg, len, "attribute %s of %s is not %s", it->name, it->object, want);
  else if (it->kind == KERGS_H5_ATTR_INT && H5Aread(attr, H5T_NATIVE_LLONG, value) < 0)
    (void)PetscSNPrintf(msg, len, "attribute %s of %s cannot be read as an integer", it->name, it->object);
  if (space >= 0) (void)H5Sclose(space);
  if (type >= 0) (void)H5Tclose(type);
  if (attr >= 0) (void)H5Aclose(attr);
}

/* A dataset holds rows x width numbers ((rows) or (rows, 1) when width is 1). */
static void ProbeDataset(hid_t file, const KergsH5Item *it, PetscInt rows, char msg[], size_t len)
{
  char        full[PETSC_MAX_PATH_LEN];
  hid_t       set, type, space;
  hsize_t     dims[3] = {0, 0, 0};
  int         ndims;
  H5T_class_t cls;
  PetscBool   ok;

  (void)PetscSNPrintf(full, sizeof(full), "%s/%s", it->object, it->name);
  set = H5Lexists(file, full, H5P_DEFAULT) > 0 ? H5Dopen2(file, full, H5P_DEFAULT) : -1;
  if (set < 0) {
    (void)PetscSNPrintf(msg, len, "has no dataset %s", full);
    return;
  }
  type  = H5Dget_type(set);
  space = H5Dget_space(set);
  cls   = type >= 0 ? H5Tget_class(type) : H5T_NO_CLASS;
  ndims = space >= 0 ? H5Sget_simple_extent_ndims(space) : -1;
  if (ndims >= 1 && ndims <= 2) (void)H5Sget_simple_extent_dims(space, dims, NULL);
  ok = (PetscBool)((cls == H5T_FLOAT || cls == H5T_INTEGER) && ndims >= 1 && ndims <= 2 && dims[0] == (hsize_t)rows &&
                   (ndims == 1 ? it->width == 1 : dims[1] == (hsize_t)it->width));
  if (cls != H5T_FLOAT && cls != H5T_INTEGER)
    (void)PetscSNPrintf(msg, len, "dataset %s does not hold numbers", full);
  else if (!ok)
    (void)PetscSNPrintf(msg, len, "dataset %s is not %" PetscInt_FMT " x %" PetscInt_FMT " numbers (its %d dimensions: %llu x %llu)", full,
                        rows, it->width, ndims, (unsigned long long)dims[0], (unsigned long long)(ndims == 2 ? dims[1] : 1));
  if (space >= 0) (void)H5Sclose(space);
  if (type >= 0) (void)H5Tclose(type);
  (void)H5Dclose(set);
}

PetscErrorCode KergsH5CheckItems(MPI_Comm comm, const char path[], const char what[], PetscInt n, const KergsH5Item items[])
{
  char        msg[PETSC_MAX_PATH_LEN + 256] = "", why[PETSC_MAX_PATH_LEN + 128] = "";
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(comm, &rank));
  if (rank == 0) {
    KergsH5Quiet quiet;
    hid_t        file;
    long long    last = -1;

    KergsH5QuietBegin(&quiet);
    file = H5Fopen(path, H5F_ACC_RDONLY, H5P_DEFAULT);
    if (file < 0) PetscCall(PetscSNPrintf(why, sizeof(why), "cannot be opened as HDF5"));
    for (PetscInt k = 0; file >= 0 && k < n && !why[0]; k++) {
      if (items[k].kind == KERGS_H5_DATASET)
        ProbeDataset(file, &items[k], items[k].rows < 0 ? (PetscInt)last : items[k].rows, why, sizeof(why));
      else
        ProbeAttribute(file, &items[k], &last, why, sizeof(why));
    }
    if (file >= 0) (void)H5Fclose(file);
    KergsH5QuietEnd(&quiet);
    if (why[0]) PetscCall(PetscSNPrintf(msg, sizeof(msg), "%s %s: %s", what, path, why));
  }
  PetscCallMPI(MPI_Bcast(msg, (int)sizeof(msg), MPI_CHAR, 0, comm));
  PetscCheck(msg[0] == 0, comm, PETSC_ERR_FILE_UNEXPECTED, "%s", msg);
  PetscFunctionReturn(0);
}
