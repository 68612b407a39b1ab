/* kergs XDMF: the text file that lets ParaView (its "XDMF Reader", Xdmf 2) open a results file's snapshots as a time
   series, written beside the results file by the results writer (src/io/results.c, -output_xdmf) and described in
   docs/results.md, "XDMF file for ParaView". It holds no data: every array is a reference to a dataset of
   /snapshots/<k> in the HDF5 file. Three temporal collections (the reader's blocks, named alike at every time), each
   with one grid per snapshot:
     disks     n points (Polyvertex cells), point attributes radius, v, omega, rot, id, material
     contacts  m lines (Polyline of 2 nodes) from the dataset segment, cell attributes rn, rt (columns of r), n, gap, kind
     walls     w lines from the dataset walls, cell attribute infinite */
#ifndef KERGS_XDMF_H
#define KERGS_XDMF_H

#include <petscsys.h>

/* What the XDMF file needs of one snapshot group (its attributes). */
typedef struct {
  PetscInt  step;
  PetscReal time;
  PetscInt  ndisks, nwalls, ncontacts;
} KergsXdmfSnapshot;

/* The XDMF path of a results file: its path with .h5 replaced by .xdmf (.xdmf appended without .h5). */
PETSC_EXTERN PetscErrorCode KergsXdmfPath(const char results[], char xdmf[], size_t len);
/* Writes path (through path.tmp, renamed when complete) listing snapshots [0, n) of the HDF5 file h5file, which is named
   relative to the XDMF file's directory. Not collective: call it on one rank. A failed write removes path.tmp and says
   why ("No space left on device", ...). */
PETSC_EXTERN PetscErrorCode KergsXdmfWrite(const char path[], const char h5file[], PetscInt n, const KergsXdmfSnapshot snap[]);

#endif
