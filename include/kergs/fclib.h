/* kergs FCLib: one step's local contact problem written in the FCLib HDF5 format (-fclib_output, src/io/fclib_export.c),
   and FCLib problems read back (-fclib_input, src/io/fclib_import.c). Layout in docs/results.md. */
#ifndef KERGS_FCLIB_H
#define KERGS_FCLIB_H

#include <kergs/operators.h>

PETSC_EXTERN PetscErrorCode KergsFCLibExport(KergsScene, KergsContacts, KergsOperators, const PetscBool *active, const char path[]);
/* An -fclib_input run's problem with the impulses the solver found as its solution (every contact), titled after the
   source file: what -fclib_output writes there. Collective. */
PETSC_EXTERN PetscErrorCode KergsFCLibExportSolved(KergsContacts, KergsOperators, const char source[], const char path[]);

/* A 2D FCLib problem as kergs solves it: u = W r + q with Coulomb's law per contact (normal then tangential component).
   W (symmetric, m = 2 ncontacts) in compressed rows, sorted columns, no duplicates. From a global problem (M, H, f, w)
   W = H^T M^-1 H and q = H^T M^-1 f + w. The whole problem on every rank. */
typedef struct {
  PetscInt   ncontacts, m, nnz;
  PetscInt  *rowptr, *colind;
  PetscReal *val, *q, *mu;
  PetscReal *r_ref;  /* the solution stored in the file (m entries), NULL when it holds none */
  PetscBool  global; /* read from a global problem */
  char       title[256];
} KergsFCLibProblem;
/* Reads path on rank 0 (libfclib, after checking with HDF5 that it is an FCLib file libfclib can read), checks it (2D,
   sizes, indices, finite values, mu >= 0, W symmetric) and gives it to every rank. Errors name the file and the fault.
   Collective. */
PETSC_EXTERN PetscErrorCode KergsFCLibRead(MPI_Comm, const char path[], KergsFCLibProblem *);
PETSC_EXTERN PetscErrorCode KergsFCLibProblemFree(KergsFCLibProblem *);
/* io internal: a function of libfclib (loaded once with dlopen, rank 0); msg is set when missing */
PETSC_INTERN void KergsFCLibSymbol(const char name[], void **fn, char msg[], size_t len);

#endif
