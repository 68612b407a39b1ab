/* kergs FCLib export: writes one step's local problem (W, q = v^d, mu) in the FCLib HDF5 format with
   Debian's libfclib, so that other solvers (Siconos fc2d) solve the very problem kergs solved.
   Unknowns per contact: normal then tangential; u = W r + q. Frictionless scenes are padded with a
   decoupled tangential component (W_tt = W_nn, mu = 0). Only active contacts are exported; the
   impulses kergs found are written as the problem's guess/solution. */
#ifndef KERGS_FCLIB_H
#define KERGS_FCLIB_H

#include <kergs/operators.h>

PETSC_EXTERN PetscErrorCode KergsFCLibExport(KergsScene, KergsContacts, KergsOperators, const PetscBool *active, const char path[]);

#endif
