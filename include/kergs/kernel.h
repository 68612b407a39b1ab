/* kergs kernel: the orthogonal projector onto ker H_f without a basis (DESIGN.md section 5),
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

typedef enum {
  KERGS_KERNEL_DIAG_EXACT,
  KERGS_KERNEL_DIAG_BOUND
} KergsKernelDiag;
PETSC_EXTERN const char *const KergsKernelDiags[];

typedef struct _p_KergsKernel *KergsKernel;
struct _p_KergsKernel {
  MPI_Comm        comm;
  char            solver[32];   /* -kernel_solver: auto, cholmod, mumps */
  char            used[32];     /* the factorization package actually used this step */
  KergsKernelDiag diagtype;     /* -kernel_diag */
  PetscReal       omega;
  /* this step's reduced problem */
  Mat       Hr;                 /* reduced H_f^T: kept contact components x kept DOFs */
  IS        keep_rows, keep_cols; /* kept DOFs (global free DOF numbers), kept contact components */
  Mat       A, F;               /* A = Hr^T Hr (DOF space) and its factor */
  Mat       Z;                  /* MATSHELL over all contact components: x -> omega P x */
  PetscReal *Zdiag;             /* per local contact, ncomp x ncomp row-major blocks of Z */
  PetscInt  ncomp, nlocal;      /* components per contact, local contacts */
  /* statistics of this step */
  PetscInt  ncols;              /* contact components (columns of H_f) */
  PetscInt  nrows;              /* free DOFs (rows of H_f) */
  PetscInt  rank;               /* rank of H_f */
  PetscInt  floating_grains;    /* grains without contact */
  PetscInt  peeled_contacts;    /* contacts removed because they end on a single-contact grain */
  PetscInt  deficiency_peeled;  /* rank lost by the peeled grains */
  PetscInt  null_pivots;        /* remaining deficiency found by the factorization */
  PetscInt  nnz_factor;         /* entries of the factor (0 when the package does not tell) */
  PetscReal factor_seconds, diag_seconds;
  /* work */
  Vec xr, yr, ar, br;           /* reduced contact and DOF vectors */
  VecScatter to_reduced;        /* all contact components -> kept ones */
  /* added with the implementation (src/kernel.c) */
  PetscReal null_pivot_tol;     /* -kernel_null_pivot_tol: MUMPS CNTL(3); CHOLMOD is rejected above condition 1/tol */
  PetscReal check_tol;          /* -kernel_check_tol: largest |H_f P x| / |H_f x| accepted after each factorization */
  PetscInt  diag_batch;         /* -kernel_diag_batch: contacts per rank in one block of right-hand sides (exact diag) */
  PetscInt  floating_dofs;      /* DOFs of bodies (grains and free walls) without contact */
  PetscInt  single_contact_grains; /* grains with exactly one contact before peeling */
  PetscInt  kept_dofs, kept_comps; /* sizes of the reduced problem: rows of A, rows of Hr */
  PetscInt  *kept_offset;       /* per local contact: local index of its first component in xr, -1 if peeled */
  PetscReal check_error;        /* this step's |H_f P x| / |H_f x| on a pseudo-random x */
  PetscReal cond_estimate;      /* CHOLMOD only: |A|_1 |A^-1 v|_1 / |v|_1 for a pseudo-random v (0 otherwise) */
  PetscBool fell_back;          /* CHOLMOD was chosen but MUMPS used this step (CHOLMOD rejected, or A singular by its sizes) */
  PetscBool nnz_known;          /* nnz_factor was reported by the package (MUMPS INFOG(29)) */
  PetscInt  nsetups, symbolic_reuses, fallbacks; /* over the kernel's life */
  PetscInt  cholmod_pause;      /* set-ups left before CHOLMOD is tried again after a rejection */
  PetscInt  napply;             /* projector applications since the last SetUp */
  PetscReal apply_seconds;      /* their total time */
  PetscInt  pattern_n, pattern_nnz; /* local rows and nonzeros of the A that F's symbolic factor was made for */
  unsigned long long pattern_hash; /* hash of its local CSR pattern */
  const PetscBool *active;      /* per local contact (KergsKernelSetActive); NULL: every contact */
  PetscBool active_only;        /* -kernel_active_only: H_f over the active contacts instead of all potential ones */
  PetscInt  inactive_contacts;  /* contacts left out because inactive: r = 0 there, not an unknown */
};

PETSC_EXTERN PetscErrorCode KergsKernelCreate(MPI_Comm, KergsKernel *);
PETSC_EXTERN PetscErrorCode KergsKernelSetFromOptions(KergsKernel);
/* Build and factor A for this step's H_f (ops->HfT); counts and timings as above. Collective. */
PETSC_EXTERN PetscErrorCode KergsKernelSetUp(KergsKernel, KergsScene, KergsContacts, KergsOperators);
PETSC_EXTERN PetscErrorCode KergsKernelSetOmega(KergsKernel, PetscReal omega);
/* The active contacts of the step. With -kernel_active_only, H_f is restricted to them (the law fixes r = 0 on
   the others) and P is zero on the other components; by default H_f spans every potential contact, as in
   Algorithm 1. The array must live until the next SetUp. NULL: every contact is active. */
PETSC_EXTERN PetscErrorCode KergsKernelSetActive(KergsKernel, const PetscBool *active);
/* y = P x (x, y over all contact components, layout of ops->r) */
PETSC_EXTERN PetscErrorCode KergsKernelProject(KergsKernel, Vec x, Vec y);
/* the MATSHELL Z = omega P (valid until the next SetUp) */
PETSC_EXTERN PetscErrorCode KergsKernelGetZ(KergsKernel, Mat *);
/* Z's diagonal blocks into kernel->Zdiag, with the current omega */
PETSC_EXTERN PetscErrorCode KergsKernelComputeDiagonalBlocks(KergsKernel);
PETSC_EXTERN PetscErrorCode KergsKernelView(KergsKernel, PetscViewer);
PETSC_EXTERN PetscErrorCode KergsKernelReset(KergsKernel);
PETSC_EXTERN PetscErrorCode KergsKernelDestroy(KergsKernel *);

#endif
