/* kergs kernel: the orthogonal projector onto ker H_f without a basis (docs/design.md: the kernel projector),
     P = I - H_f^T (H_f H_f^T)^+ H_f,   Z = omega P,
   applied matrix-free (a MATSHELL over contact components) through one sparse Cholesky factorization of
   A = H_f H_f^T per step: CHOLMOD on one rank, MUMPS on several (-kernel_solver auto|cholmod|mumps).
   Rank deficiency of H_f is handled before factoring by elimination (the paper's section on the 500-disk
   sample): DOF rows of grains with no contact are dropped; a grain with a single contact cannot balance a
   non-zero impulse, so that contact is zero in every kernel vector: its column and the grain's rows are
   removed, repeatedly (peeling). Remaining null pivots (e.g. collinear contacts) are detected by MUMPS
   (ICNTL(24)); CHOLMOD falls back to MUMPS when it meets one. The rank of H_f and its causes are logged.
   Z's diagonal blocks Z_aa = omega (I - h_a^T A^+ h_a), needed by NLGS-Jac (Algorithm 6), are computed
   exactly (-kernel_diag exact: blocks of solves with many right-hand sides) or bounded cheaply
   (-kernel_diag bound: h^T A^+ h >= |h|^4 / h^T A h per component, so the diagonal is over-estimated,
   which only damps NLGS-Jac; its fixed point does not depend on the diagonal used). */
#ifndef KERGS_KERNEL_H
#define KERGS_KERNEL_H

#include <kergs/operators.h>

typedef enum { KERGS_KERNEL_DIAG_EXACT, KERGS_KERNEL_DIAG_BOUND } KergsKernelDiag;
PETSC_EXTERN const char *const KergsKernelDiags[];

typedef struct _p_KergsKernel *KergsKernel;

PETSC_EXTERN PetscErrorCode KergsKernelCreate(MPI_Comm, KergsKernel *);
PETSC_EXTERN PetscErrorCode KergsKernelSetFromOptions(KergsKernel);
/* Its options become -<prefix>kernel_... (the owning solver's prefix) */
PETSC_EXTERN PetscErrorCode KergsKernelSetOptionsPrefix(KergsKernel, const char[]);
/* Build and factor A for this step's H_f (ops->HfT); counts and timings as above. Collective. */
PETSC_EXTERN PetscErrorCode KergsKernelSetUp(KergsKernel, KergsScene, KergsContacts, KergsOperators);
PETSC_EXTERN PetscErrorCode KergsKernelSetOmega(KergsKernel, PetscReal omega);
/* The active contacts of the step. With -kernel_active_only, H_f is restricted to them (the law fixes r = 0 on
   the others) and P is zero on the other components: the paper's choice (its Algorithm 1 keeps the contacts whose
   predicted gap is <= 0). By default H_f spans every potential contact (within the alert distance). The array must
   live until the next SetUp. NULL: every contact is active. */
PETSC_EXTERN PetscErrorCode KergsKernelSetActive(KergsKernel, const PetscBool *active);
/* Force H_f over the active contacts only, whatever -kernel_active_only says (newton's proximal term on ker W, whose
   unknowns are the active contacts' impulses). */
PETSC_EXTERN PetscErrorCode KergsKernelSetActiveOnly(KergsKernel, PetscBool);
/* y = P x (x, y over all contact components, layout of ops->r) */
PETSC_EXTERN PetscErrorCode KergsKernelProject(KergsKernel, Vec x, Vec y);
/* the MATSHELL Z = omega P (valid until the next SetUp) */
PETSC_EXTERN PetscErrorCode KergsKernelGetZ(KergsKernel, Mat *);
/* Z's diagonal blocks, with the current omega (computed, then read with KergsKernelGetDiagonalBlocks) */
PETSC_EXTERN PetscErrorCode KergsKernelComputeDiagonalBlocks(KergsKernel);
/* Per local contact, ncomp x ncomp row-major blocks Z_aa (valid until the next SetUp) */
PETSC_EXTERN PetscErrorCode KergsKernelGetDiagonalBlocks(KergsKernel, const PetscReal **Zdiag);

/* What the kernel found and cost at its last set-up (KergsKernelGetStats). */
typedef struct {
  PetscInt    ncols;           /* contact components (columns of H_f) */
  PetscInt    nrows;           /* free DOFs (rows of H_f) */
  PetscInt    rank;            /* rank of H_f: kernel dimension = ncols - rank */
  PetscInt    floating_grains; /* grains without contact */
  PetscInt    peeled_contacts; /* contacts removed because they end on a single-contact grain */
  PetscInt    null_pivots;     /* remaining deficiency found by the factorization */
  PetscInt    nnz_factor;      /* entries of the factor (0 when the package does not tell) */
  PetscReal   factor_seconds;  /* elimination, assembly and factorization of H_f H_f^T */
  PetscReal   diag_seconds;    /* diagonal blocks of Z */
  PetscReal   check_error;     /* |H_f P x| / |H_f x| on a pseudo-random x */
  PetscReal   check_tol;       /* -kernel_check_tol */
  PetscBool   check_failed;    /* check_error > check_tol even with MUMPS: the projector misses ker H_f (a failed solve) */
  const char *package;         /* factorization package used (cholmod, mumps) */
} KergsKernelStats;
PETSC_EXTERN PetscErrorCode KergsKernelGetStats(KergsKernel, KergsKernelStats *);
PETSC_EXTERN PetscErrorCode KergsKernelView(KergsKernel, PetscViewer);
PETSC_EXTERN PetscErrorCode KergsKernelReset(KergsKernel);
PETSC_EXTERN PetscErrorCode KergsKernelDestroy(KergsKernel *);

#endif
