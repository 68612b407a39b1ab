/* kergs HDF5 probes (base layer), private to the library: they need hdf5.h, which the installed headers do not. For
   the readers of src/io and src/scene (checkpoints, results files, samples, FCLib problems), which look at a file
   before PETSc's viewer or libfclib opens it. A missing, truncated, damaged or foreign file is an expected outcome
   there, so HDF5's own error trace is switched off around the probe and kergs says what is wrong instead
   (src/base/h5probe.c). */
#ifndef KERGS_H5PROBE_H
#define KERGS_H5PROBE_H

#include <petscsys.h>
#include <hdf5.h>

/* The root attribute kergs_format of a sample file (written by src/io/sample.c, read by src/scene/sample_read.c). */
#define KERGS_SAMPLE_FORMAT "kergs sample 1"

/* HDF5's automatic error printing, saved by KergsH5QuietBegin and restored by KergsH5QuietEnd. */
typedef struct {
  H5E_auto2_t handler;
  void       *data;
  PetscBool   saved;
} KergsH5Quiet;

PETSC_INTERN void KergsH5QuietBegin(KergsH5Quiet *);
PETSC_INTERN void KergsH5QuietEnd(const KergsH5Quiet *);
/* Whether the root attribute kergs_format of an open file begins with format (call between QuietBegin and QuietEnd). */
PETSC_INTERN PetscBool KergsH5HasFormat(hid_t file, const char format[]);
/* Rank 0 checks that path is a readable file that HDF5 opens and, with format not NULL, whose kergs_format is format;
   every rank raises PETSC_ERR_FILE_OPEN otherwise: "<what> <path> does not exist or is not readable", "<what> <path>
   cannot be opened as HDF5: ..." or "File <path> is not a <kind> (root attribute kergs_format is not "<format>")".
   Collective. */
PETSC_INTERN PetscErrorCode KergsH5CheckFile(MPI_Comm, const char path[], const char what[], const char format[], const char kind[]);

/* One item a reader expects in a file: an attribute of an object (a single integer, or a single fixed-length
   string, as PETSc's viewer reads them), or a numeric dataset of rows x width values ((rows) when width is 1). */
typedef enum { KERGS_H5_ATTR_INT, KERGS_H5_ATTR_STRING, KERGS_H5_DATASET } KergsH5ItemKind;
typedef struct {
  KergsH5ItemKind kind;
  const char     *object, *name; /* the object holding the attribute, or the group holding the dataset */
  PetscInt        rows, width;   /* a dataset's expected shape; rows -1: the value of the integer attribute checked last */
} KergsH5Item;
/* Rank 0 checks the n items in order; the first that is missing or of another kind, class or shape raises
   PETSC_ERR_FILE_UNEXPECTED on every rank, "<what> <path>: ..." naming it. Attributes and datasets read by PETSc's
   viewer without these checks crashed on arrays where one value was expected. Collective. */
PETSC_INTERN PetscErrorCode KergsH5CheckItems(MPI_Comm, const char path[], const char what[], PetscInt n, const KergsH5Item items[]);

#endif
