/* kergs detect, private: the contact set's fields, for src/detect/ only; every other component goes through the
   accessors of kergs/detect.h. */
#ifndef KERGS_DETECTIMPL_H
#define KERGS_DETECTIMPL_H

#include <kergs/detect.h>

struct _p_KergsContacts {
  MPI_Comm      comm;
  PetscInt      n, nalloc;      /* contacts owned by this rank */
  KergsContact *c;              /* sorted by (a, kind, idb) */
  PetscInt      nglobal, start; /* global count and global index of c[0] */
  /* foreign contacts: disk-disk contacts of another rank (their body a is a ghost here, of smaller id) whose body b
     is a disk owned here, with their global index. Together with the owned contacts they are every contact at an
     owned disk, as the assembly of W needs (each rank adds its bodies' terms). */
  PetscInt      nforeign, nforeignalloc;
  KergsContact *foreign;
  PetscInt     *foreign_index;
  /* previous detection, for persistence, sorted by (a, kind, idb); exists only during a detection */
  PetscInt             nprev;
  KergsContactHistory *prev;
  /* broad-phase workspace: cell list over the bounding box of the disk centres, rebuilt by every call.
     cellhead[cell] is the highest disk index in the cell (-1: empty), next[i] the next lower index in
     disk i's cell (-1: end), so a walk visits a cell's disks in decreasing index order. */
  PetscInt  ncellx, ncelly, ncellalloc, *cellhead, *next;
  PetscInt  nnextalloc; /* capacity of next[] */
  PetscReal cellsize, origin[KERGS_DIM];
};

#endif
