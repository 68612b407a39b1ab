/* kergs kernel: the orthogonal projector onto ker H_f, P = I - H_f^T (H_f H_f^T)^+ H_f, and Z = omega P
   (docs/design.md: the kernel projector; the paper's Algorithm 6 needs Z's products and diagonal blocks, never Z itself).

   Per step (KergsKernelSetUp):
   1. Elimination (the paper's section on the 500-disk sample). Bodies are the disks and the free walls
      (driven walls are not DOFs). A body without contact contributes empty rows to H_f: they are dropped.
      A body with a single contact alpha cannot balance a non-zero impulse of alpha (its rows of H_f restricted
      to alpha's columns, n and t and the lever arm, have full column rank), so r_alpha = 0 in every kernel
      vector: alpha's columns and, once empty, the body's rows are removed, repeatedly (peeling a tree of
      contacts hanging off the packing). With H_f = [B 0; C H'] (B: the body's rows x alpha's columns, full
      column rank), ker H_f = {0} x ker H' and rank H_f = ncomp + rank H': each peeled contact adds ncomp to
      the rank, and the reduced Hr has the same kernel as H_f on the kept components.
   2. Hr = the kept rows (contact components) and columns (DOFs) of H_f^T, with every rotational column scaled
      by 1 / radius (a row scaling of H_f: same kernel, same projector, but A has entries of one unit).
   3. A = Hr^T Hr (DOF space), a sparse Cholesky factorization: CHOLMOD on one rank, MUMPS on several; MUMPS
      detects the remaining null pivots (ICNTL(24) = 1, threshold CNTL(3) = -kernel_null_pivot_tol); a failed or
      numerically singular CHOLMOD factorization falls back to MUMPS (and CHOLMOD then rests for a few set-ups).
      The symbolic factorization is reused when A has the same layout and CSR pattern as at the previous step.
      The factorizations read their package options with the prefix kernel_ (-kernel_mat_mumps_icntl_14 ...).
   4. A self-check on a pseudo-random x: |Hr^T P xr| <= -kernel_check_tol |Hr^T xr|.
   rank H_f = ncomp * peeled contacts + (rows of A) - (null pivots).
   A guided free wall (docs/design.md) has rows of H_f that are multiples of its normal n: only its larger component's
   row is kept (the other is proportional to it, or zero, and counts with the floating DOFs as a row without rank), and
   with friction it peels nothing (one contact's tangential impulse is not balanced by the wall).

   P x = 0 on the peeled components, and xr - Hr y with A y = Hr^T xr on the kept ones: a generalized inverse
   from the null-pivot fixation gives the same Hr y, since Hr^T xr lies in range(A). */
#include <kergs/private/kernelimpl.h>
#include <petscmat.h>

const char *const KergsKernelDiags[] = {"exact", "bound", "KergsKernelDiag", "KERGS_KERNEL_DIAG_", NULL};

/* Options of the kernel's factorizations: -kernel_mat_mumps_icntl_14 50, -kernel_mat_cholmod_print 3, ... */
#define KERGS_KERNEL_FACTOR_PREFIX "kernel_"

PetscErrorCode KergsKernelCreate(MPI_Comm comm, KergsKernel *kernel)
{
  KergsKernel k;

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCall(PetscNew(&k));
  k->comm           = comm;
  k->diagtype       = KERGS_KERNEL_DIAG_BOUND; /* exact costs seconds at 20,000 grains against milliseconds */
  k->omega          = 1.0;
  k->null_pivot_tol = 1e-10;
  k->check_tol      = 1e-8;
  k->diag_batch     = 32;
  PetscCall(PetscStrncpy(k->solver, "auto", sizeof(k->solver)));
  PetscCall(PetscStrncpy(k->used, "none", sizeof(k->used)));
  *kernel = k;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelSetFromOptions(KergsKernel k)
{
  const char *solvers[] = {"auto", "cholmod", "mumps"};
  PetscInt    which     = 0;
  PetscMPIInt size;

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < 3; i++) {
    PetscBool same;
    PetscCall(PetscStrcmp(k->solver, solvers[i], &same));
    if (same) which = i;
  }
  PetscOptionsBegin(k->comm, k->prefix[0] ? k->prefix : NULL, "Kernel projector options (P = I - H_f^T (H_f H_f^T)^+ H_f)", NULL);
  PetscCall(PetscOptionsEList(
      "-kernel_solver", "Sparse Cholesky package for H_f H_f^T: auto (cholmod on 1 rank, mumps on several), cholmod (1 rank only), mumps",
      "KergsKernelSetUp", solvers, 3, solvers[which], &which, NULL));
  PetscCall(PetscOptionsEnum("-kernel_diag",
                             "Diagonal blocks of Z for NLGS-Jac: exact (blocks of solves) or bound (cheap over-estimate of each diagonal "
                             "entry, off-diagonal entries 0)",
                             "KergsKernelComputeDiagonalBlocks", KergsKernelDiags, (PetscEnum)k->diagtype, (PetscEnum *)&k->diagtype,
                             NULL));
  PetscCall(KergsOptionsBool(PetscOptionsObject, "-kernel_active_only",
                             "Kernel of H_f over the active contacts only (default: every potential contact, as in Algorithm 1)",
                             "KergsKernelSetActive", k->active_only, &k->active_only, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-kernel_diag_batch", "Exact diagonal: contacts per rank in one block of right-hand sides",
                            "KergsKernelComputeDiagonalBlocks", k->diag_batch, &k->diag_batch, NULL));
  PetscCall(PetscOptionsReal("-kernel_null_pivot_tol",
                             "Pivots below this times |A| are null (MUMPS CNTL(3)); CHOLMOD is rejected above condition 1/tol",
                             "KergsKernelSetUp", k->null_pivot_tol, &k->null_pivot_tol, NULL));
  PetscCall(PetscOptionsReal("-kernel_check_tol",
                             "Largest |H_f P x| / |H_f x| accepted after a factorization (checked on a pseudo-random x)",
                             "KergsKernelSetUp", k->check_tol, &k->check_tol, NULL));
  PetscOptionsEnd();
  PetscCall(PetscStrncpy(k->solver, solvers[which], sizeof(k->solver)));
  PetscCallMPI(MPI_Comm_size(k->comm, &size));
  PetscCheck(which != 1 || size == 1, k->comm, PETSC_ERR_ARG_INCOMP,
             "-kernel_solver cholmod is sequential only (%d ranks here): use -kernel_solver mumps or auto", (int)size);
  PetscCheck(k->diag_batch >= 1, k->comm, PETSC_ERR_ARG_OUTOFRANGE, "-kernel_diag_batch %" PetscInt_FMT " must be at least 1",
             k->diag_batch);
  PetscCheck(k->null_pivot_tol > 0 && k->null_pivot_tol < 1, k->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-kernel_null_pivot_tol %g must be in (0,1)", (double)k->null_pivot_tol);
  PetscCheck(k->check_tol > 0 && PetscIsNormalReal(k->check_tol), k->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-kernel_check_tol %g must be positive", (double)k->check_tol);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelSetActive(KergsKernel k, const PetscBool *active)
{
  PetscFunctionBeginUser;
  k->active = active;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelSetActiveOnly(KergsKernel k, PetscBool only)
{
  PetscFunctionBeginUser;
  k->active_only = only;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelSetOmega(KergsKernel k, PetscReal omega)
{
  PetscFunctionBeginUser;
  PetscCheck(omega > 0 && PetscIsNormalReal(omega), k->comm, PETSC_ERR_ARG_OUTOFRANGE, "Kernel projector: omega %g must be positive",
             (double)omega);
  k->omega = omega;
  PetscFunctionReturn(0);
}

/* The objects of one step; the factor F survives so that its symbolic part can be reused. */
static PetscErrorCode DestroyStepObjects(KergsKernel k)
{
  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&k->Hr));
  PetscCall(MatDestroy(&k->A));
  PetscCall(MatDestroy(&k->Z));
  PetscCall(ISDestroy(&k->keep_rows));
  PetscCall(ISDestroy(&k->keep_cols));
  PetscCall(VecDestroy(&k->xr));
  PetscCall(VecDestroy(&k->yr));
  PetscCall(VecDestroy(&k->ar));
  PetscCall(VecDestroy(&k->br));
  PetscCall(VecScatterDestroy(&k->to_reduced));
  PetscCall(PetscFree(k->kept_offset));
  PetscCall(PetscFree(k->Zdiag));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelReset(KergsKernel k)
{
  PetscFunctionBeginUser;
  PetscCall(DestroyStepObjects(k));
  PetscCall(MatDestroy(&k->F));
  k->pattern_hash = 0;
  k->pattern_n = k->pattern_nnz = -1;
  k->cholmod_pause              = 0;
  PetscCall(PetscStrncpy(k->used, "none", sizeof(k->used)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelSetOptionsPrefix(KergsKernel k, const char prefix[])
{
  PetscFunctionBeginUser;
  PetscCall(PetscStrncpy(k->prefix, prefix ? prefix : "", sizeof(k->prefix)));
  PetscFunctionReturn(0);
}

/* The prefix of the factorization's options: the kernel's, then kernel_ (-kernel_mat_mumps_icntl_14) */
static PetscErrorCode FactorPrefix(KergsKernel k, char prefix[], size_t len)
{
  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(prefix, len, "%s%s", k->prefix, KERGS_KERNEL_FACTOR_PREFIX));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelDestroy(KergsKernel *k)
{
  PetscFunctionBeginUser;
  if (!*k) PetscFunctionReturn(0);
  PetscCall(KergsKernelReset(*k));
  PetscCall(PetscFree(*k));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Elimination: floating bodies and peeling                                                          */

/* What the kernel reads from the scene, the contacts and the operators, through their accessors. */
typedef struct {
  KergsDisks       D;
  const KergsWall *walls;
  PetscInt         nwalls, ncontacts, nglobal, start;
  KergsContact    *c;
  KergsDofLayout   L;
  Mat              HfT;
  Vec              r, Vf;
} KernelInput;

static PetscErrorCode GetKernelInput(KergsScene scene, KergsContacts contacts, KergsOperators ops, KernelInput *in)
{
  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(scene, &in->D));
  PetscCall(KergsSceneGetWalls(scene, &in->nwalls, &in->walls));
  PetscCall(KergsContactsGetLocal(contacts, &in->ncontacts, &in->c));
  PetscCall(KergsContactsGetGlobalRange(contacts, &in->start, &in->nglobal));
  PetscCall(KergsOperatorsGetLayout(ops, &in->L));
  PetscCall(KergsOperatorsGetH(ops, &in->HfT, NULL));
  PetscCall(KergsOperatorsGetContactVectors(ops, &in->r, NULL, NULL));
  PetscCall(KergsOperatorsGetDofVectors(ops, &in->Vf, NULL, NULL, NULL));
  PetscFunctionReturn(0);
}

/* Bodies: disks 0..ndisks-1, then the free walls; -1 for a driven wall (not a DOF of H_f). */
static PetscInt BodyOfWall(const KernelInput *in, PetscInt w)
{
  if (in->walls[w].kind != KERGS_WALL_FREE) return -1;
  return in->D.ndisks + (in->L.wall_dof[w] - in->D.ndisks * in->L.ndof_disk) / KERGS_DIM;
}

/* The free wall that is body b (b >= ndisks), or -1 for a disk. */
static PetscInt WallOfBody(const KernelInput *in, PetscInt b)
{
  if (b < in->D.ndisks) return -1;
  for (PetscInt w = 0; w < in->nwalls; w++)
    if (BodyOfWall(in, w) == b) return w;
  return -1;
}

/* A guided wall (docs/design.md) moves along its normal n only: its two columns of H_f^T are multiples of n_x and n_y,
   so one of them, the larger component's, carries its whole rank (1), and with ncomp = 2 one contact at it leaves the
   tangential impulse unbalanced by the wall: the wall cannot peel that contact (its block has rank 1, not 2). */
static PetscBool GuidedBody(const KernelInput *in, PetscInt b)
{
  PetscInt w = WallOfBody(in, b);
  return (PetscBool)(w >= 0 && in->walls[w].guided);
}

/* Whether free DOF g is kept in Hr: every DOF of a body with a live contact, except a guided wall's smaller component. */
static PetscBool KeptDof(const KernelInput *in, PetscInt g, PetscInt b)
{
  PetscReal n[KERGS_DIM];

  if (!GuidedBody(in, b)) return PETSC_TRUE;
  KergsWallNormal(&in->walls[WallOfBody(in, b)], n);
  return (PetscBool)((g - in->D.ndisks * in->L.ndof_disk) % KERGS_DIM == (PetscAbsReal(n[1]) > PetscAbsReal(n[0]) ? 1 : 0));
}

static PetscInt BodyOfDof(const KernelInput *in, PetscInt dof)
{
  PetscInt ndisk_dofs = in->D.ndisks * in->L.ndof_disk;
  return dof < ndisk_dofs ? dof / in->L.ndof_disk : in->D.ndisks + (dof - ndisk_dofs) / KERGS_DIM;
}

/* Both bodies (global indices) of every contact of every rank, in global contact order (2 per contact). Peeling
   runs on this replicated graph (2 integers per contact on every rank): at hundreds of ranks it would have to
   become a distributed peeling. */
static PetscErrorCode GatherContactBodies(KergsKernel k, const KernelInput *in, PetscInt **ends)
{
  PetscMPIInt size, nmine = (PetscMPIInt)(2 * in->ncontacts), *counts, *displs;
  PetscInt   *mine;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(k->comm, &size));
  PetscCall(PetscMalloc1(2 * in->ncontacts + 1, &mine));
  PetscCall(PetscMalloc1(2 * in->nglobal + 1, ends));
  for (PetscInt c = 0; c < in->ncontacts; c++) {
    const KergsContact *ct = &in->c[c];
    if (k->active_only && k->active && !k->active[c]) { /* an inactive contact has no ends: it never takes part */
      mine[2 * c] = mine[2 * c + 1] = -1;
      continue;
    }
    mine[2 * c]     = in->D.gidx[ct->a];
    mine[2 * c + 1] = ct->kind == KERGS_CONTACT_DISK_DISK ? in->D.gidx[ct->b] : BodyOfWall(in, ct->b);
  }
  PetscCall(PetscMalloc2(size, &counts, size + 1, &displs));
  PetscCallMPI(MPI_Allgather(&nmine, 1, MPI_INT, counts, 1, MPI_INT, k->comm));
  displs[0] = 0;
  for (PetscMPIInt p = 0; p < size; p++) displs[p + 1] = displs[p] + counts[p];
  PetscCheck(displs[size] == 2 * in->nglobal, k->comm, PETSC_ERR_PLIB, "Kernel: %d contact ends gathered for %" PetscInt_FMT " contacts",
             displs[size], in->nglobal);
  PetscCallMPI(MPI_Allgatherv(mine, nmine, MPIU_INT, *ends, counts, displs, MPIU_INT, k->comm));
  PetscCall(PetscFree2(counts, displs));
  PetscCall(PetscFree(mine));
  PetscFunctionReturn(0);
}

/* Peel the contact graph: while a body that can (peels[b]) has a single live contact, kill that contact. alive[c] per global
   contact; count[b] = live contacts of body b on exit, count0[b] before. Every rank runs the same sequential
   algorithm on the same data, so every rank gets the same answer. A queue makes it O(bodies + contacts). */
static PetscErrorCode PeelContacts(PetscInt nbodies, PetscInt ncontacts, const PetscInt *ends, const PetscBool *peels, PetscBool *alive,
                                   PetscInt *count0, PetscInt *count)
{
  PetscInt *start, *adj, *fill, *queue, qhead = 0, qtail = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscArrayzero(count0, nbodies));
  for (PetscInt e = 0; e < 2 * ncontacts; e++)
    if (ends[e] >= 0) count0[ends[e]]++;
  PetscCall(PetscArraycpy(count, count0, nbodies));
  /* body -> contacts adjacency in CSR form */
  PetscCall(PetscMalloc4(nbodies + 1, &start, 2 * ncontacts + 1, &adj, nbodies, &fill, 2 * nbodies + 2 * ncontacts + 1, &queue));
  start[0] = 0;
  for (PetscInt b = 0; b < nbodies; b++) start[b + 1] = start[b] + count0[b];
  PetscCall(PetscArraycpy(fill, start, nbodies));
  for (PetscInt e = 0; e < 2 * ncontacts; e++)
    if (ends[e] >= 0) adj[fill[ends[e]]++] = e / 2;
  for (PetscInt c = 0; c < ncontacts; c++) alive[c] = (PetscBool)(ends[2 * c] >= 0); /* body a is a disk: -1 marks an inactive contact */
  for (PetscInt b = 0; b < nbodies; b++)
    if (count[b] == 1 && peels[b]) queue[qtail++] = b;
  /* each body enters the queue at most once per decrement of its count, plus once initially */
  while (qhead < qtail) {
    PetscInt b = queue[qhead++], c = -1;
    if (count[b] != 1) continue;
    for (PetscInt j = start[b]; j < start[b + 1]; j++)
      if (alive[adj[j]]) c = adj[j];
    alive[c] = PETSC_FALSE;
    for (PetscInt s = 0; s < 2; s++) {
      PetscInt o = ends[2 * c + s];
      if (o < 0) continue;
      count[o]--;
      if (count[o] == 1 && peels[o]) queue[qtail++] = o;
    }
  }
  PetscCall(PetscFree4(start, adj, fill, queue));
  PetscFunctionReturn(0);
}

/* Kept DOFs (this rank's, global free DOF numbers) and kept contact components (this rank's), and the
   statistics of the elimination. */
static PetscErrorCode Eliminate(KergsKernel k, const KernelInput *in)
{
  PetscInt   nbodies = in->D.ndisks + in->L.nfreewalls, nc = in->L.ncomp, *ends, *count0, *count, lo, hi, nkeep = 0, *idx;
  PetscBool *alive, *peels;
  PetscInt   peeled_dofs = 0;

  PetscFunctionBeginUser;
  PetscCall(GatherContactBodies(k, in, &ends));
  PetscCall(PetscMalloc4(in->nglobal + 1, &alive, nbodies + 1, &count0, nbodies + 1, &count, nbodies + 1, &peels));
  for (PetscInt b = 0; b < nbodies; b++) peels[b] = (PetscBool)(nc == 1 || !GuidedBody(in, b));
  PetscCall(PeelContacts(nbodies, in->nglobal, ends, peels, alive, count0, count));
  k->floating_grains = k->floating_dofs = k->single_contact_grains = k->peeled_contacts = 0;
  for (PetscInt b = 0; b < nbodies; b++) {
    PetscInt ndof = b < in->D.ndisks ? in->L.ndof_disk : KERGS_DIM;
    if (count0[b] == 0) {
      k->floating_dofs += ndof;
      if (b < in->D.ndisks) k->floating_grains++;
    } else if (count[b] == 0)
      peeled_dofs += ndof;
    if (b < in->D.ndisks && count0[b] == 1) k->single_contact_grains++;
    if (count[b] > 0 && GuidedBody(in, b)) k->floating_dofs += KERGS_DIM - 1; /* its rows beyond the one kept carry no rank */
  }
  k->inactive_contacts = 0;
  for (PetscInt c = 0; c < in->nglobal; c++) {
    if (ends[2 * c] < 0)
      k->inactive_contacts++;
    else if (!alive[c])
      k->peeled_contacts++;
  }
  /* rows of the peeled bodies minus the rank their contacts carry (ncomp each) */
  k->deficiency_peeled = peeled_dofs - nc * k->peeled_contacts;

  /* kept DOFs: those of bodies with a live contact */
  PetscCall(VecGetOwnershipRange(in->Vf, &lo, &hi));
  PetscCall(PetscMalloc1(hi - lo + 1, &idx));
  for (PetscInt g = lo; g < hi; g++)
    if (count[BodyOfDof(in, g)] > 0 && KeptDof(in, g, BodyOfDof(in, g))) idx[nkeep++] = g;
  PetscCall(ISCreateGeneral(k->comm, nkeep, idx, PETSC_OWN_POINTER, &k->keep_rows));

  /* kept contact components, and where each local contact's components sit in the reduced vectors */
  PetscCall(PetscMalloc1(in->ncontacts + 1, &k->kept_offset));
  PetscCall(PetscMalloc1(in->ncontacts * nc + 1, &idx));
  nkeep = 0;
  for (PetscInt c = 0; c < in->ncontacts; c++) {
    PetscInt gc       = in->start + c;
    k->kept_offset[c] = alive[gc] ? nkeep : -1;
    if (alive[gc])
      for (PetscInt j = 0; j < nc; j++) idx[nkeep++] = gc * nc + j;
  }
  PetscCall(ISCreateGeneral(k->comm, nkeep, idx, PETSC_OWN_POINTER, &k->keep_cols));
  PetscCall(PetscFree4(alive, count0, count, peels));
  PetscCall(PetscFree(ends));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Reduced system and factorization                                                                 */

/* Hr = kept rows (components) and columns (DOFs) of H_f^T; rotational columns scaled by 1/radius. */
static PetscErrorCode BuildReducedOperator(KergsKernel k, const KernelInput *in)
{
  const PetscInt *dofs;
  PetscScalar    *s;
  PetscInt        n;
  char            prefix[256];

  PetscFunctionBeginUser;
  PetscCall(MatCreateSubMatrix(in->HfT, k->keep_cols, k->keep_rows, MAT_INITIAL_MATRIX, &k->Hr));
  PetscCall(MatCreateVecs(k->Hr, &k->ar, &k->xr));
  PetscCall(VecDuplicate(k->ar, &k->br));
  PetscCall(VecDuplicate(k->xr, &k->yr));
  PetscCall(ISGetLocalSize(k->keep_rows, &n));
  PetscCall(ISGetIndices(k->keep_rows, &dofs));
  PetscCall(VecGetArray(k->ar, &s));
  for (PetscInt i = 0; i < n; i++) {
    PetscInt b = BodyOfDof(in, dofs[i]);
    /* a local DOF belongs to an owned disk (local index b - dstart) or to a free wall */
    s[i] = (b < in->D.ndisks && dofs[i] - KergsDiskDof(&in->L, b) >= KERGS_DIM) ? 1.0 / in->D.radius[b - in->D.dstart] : 1.0;
  }
  PetscCall(VecRestoreArray(k->ar, &s));
  PetscCall(ISRestoreIndices(k->keep_rows, &dofs));
  PetscCall(MatDiagonalScale(k->Hr, NULL, k->ar));
  PetscCall(MatTransposeMatMult(k->Hr, k->Hr, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &k->A));
  /* symmetric, but not MAT_SPD: MUMPS would then skip its null-pivot detection */
  PetscCall(MatSetOption(k->A, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(FactorPrefix(k, prefix, sizeof(prefix)));
  PetscCall(MatSetOptionsPrefixFactor(k->A, prefix));
  PetscCall(VecScatterCreate(in->r, k->keep_cols, k->xr, NULL, &k->to_reduced));
  PetscCall(MatGetSize(k->A, &k->kept_dofs, NULL));
  PetscCall(MatGetSize(k->Hr, &k->kept_comps, NULL));
  PetscFunctionReturn(0);
}

/* FNV-1a over integers. */
static void HashInts(unsigned long long *h, PetscInt n, const PetscInt *v)
{
  for (PetscInt i = 0; i < n; i++) {
    unsigned long long x = (unsigned long long)v[i];
    for (int b = 0; b < 8; b++) {
      *h ^= (x >> (8 * b)) & 0xff;
      *h *= 1099511628211ULL;
    }
  }
}

static PetscErrorCode HashSeqPattern(Mat M, unsigned long long *h, PetscInt *nnz)
{
  const PetscInt *ia, *ja;
  PetscInt        n;
  PetscBool       done;

  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(M, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_SUP, "Kernel: cannot read the CSR pattern of H_f H_f^T");
  HashInts(h, 1, &n);
  HashInts(h, n + 1, ia);
  HashInts(h, ia[n], ja);
  *nnz += ia[n];
  PetscCall(MatRestoreRowIJ(M, 0, PETSC_FALSE, PETSC_FALSE, &n, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

/* Local rows, nonzeros and hash of the local CSR pattern of A (diagonal and off-diagonal blocks and the
   off-diagonal block's global columns for MPIAIJ). */
static PetscErrorCode PatternOf(Mat A, PetscInt *n, PetscInt *nnz, unsigned long long *h)
{
  PetscBool mpi;

  PetscFunctionBeginUser;
  *h   = 14695981039346656037ULL;
  *nnz = 0;
  PetscCall(MatGetLocalSize(A, n, NULL));
  PetscCall(PetscObjectTypeCompare((PetscObject)A, MATMPIAIJ, &mpi));
  if (mpi) {
    Mat             Ad, Ao;
    const PetscInt *garray;
    PetscInt        nco;
    PetscCall(MatMPIAIJGetSeqAIJ(A, &Ad, &Ao, &garray));
    PetscCall(MatGetSize(Ao, NULL, &nco));
    PetscCall(HashSeqPattern(Ad, h, nnz));
    PetscCall(HashSeqPattern(Ao, h, nnz));
    HashInts(h, nco, garray);
  } else
    PetscCall(HashSeqPattern(A, h, nnz));
  PetscFunctionReturn(0);
}

static PetscErrorCode IsSolver(KergsKernel k, const char *name, PetscBool *same)
{
  PetscFunctionBeginUser;
  PetscCall(PetscStrcmp(k->used, name, same));
  PetscFunctionReturn(0);
}

/* Numeric factorization of A into F. CHOLMOD raises an error on a matrix that is not positive definite: it is
   caught and reported through *ok. MUMPS fails silently (INFOG(1) < 0, NaN from MatSolve): its error state is
   checked, and a failure there is an error, MUMPS being the last resort. */
static PetscErrorCode FactorNumeric(KergsKernel k, PetscBool *ok)
{
  MatFactorInfo  info;
  PetscBool      cholmod;
  MatFactorError err;

  PetscFunctionBeginUser;
  PetscCall(MatFactorInfoInitialize(&info));
  PetscCall(IsSolver(k, MATSOLVERCHOLMOD, &cholmod));
  *ok = PETSC_TRUE;
  if (cholmod) {
    PetscErrorCode ierr;
    PetscCall(PetscPushErrorHandler(PetscReturnErrorHandler, NULL));
    ierr = MatCholeskyFactorNumeric(k->F, k->A, &info);
    PetscCall(PetscPopErrorHandler());
    if (ierr) {
      PetscCall(PetscInfo(NULL,
                          "Kernel: CHOLMOD factorization of H_f H_f^T (%" PetscInt_FMT " rows) failed (error %d: not positive definite)\n",
                          k->kept_dofs, (int)ierr));
      *ok = PETSC_FALSE;
    }
    PetscFunctionReturn(0);
  }
  PetscCall(MatCholeskyFactorNumeric(k->F, k->A, &info));
  PetscCall(MatFactorGetError(k->F, &err));
  if (err) {
    PetscInt infog1, infog2;
    PetscCall(MatMumpsGetInfog(k->F, 1, &infog1));
    PetscCall(MatMumpsGetInfog(k->F, 2, &infog2));
    SETERRQ(k->comm, PETSC_ERR_LIB,
            "Kernel: MUMPS factorization of H_f H_f^T (%" PetscInt_FMT " rows) failed: INFOG(1) = %" PetscInt_FMT
            ", INFOG(2) = %" PetscInt_FMT " (factor error %d); try -kernel_null_pivot_tol",
            k->kept_dofs, infog1, infog2, (int)err);
  }
  PetscFunctionReturn(0);
}

/* A new factor of A with the given package: symbolic and numeric. */
static PetscErrorCode FactorFresh(KergsKernel k, const char *solver, PetscBool *ok)
{
  MatFactorInfo info;
  IS            rperm, cperm;
  PetscBool     mumps;

  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&k->F));
  PetscCall(PetscStrncpy(k->used, solver, sizeof(k->used)));
  PetscCall(MatGetFactor(k->A, solver, MAT_FACTOR_CHOLESKY, &k->F));
  PetscCall(PetscStrcmp(solver, MATSOLVERMUMPS, &mumps));
  if (mumps) {
    PetscCall(MatMumpsSetIcntl(k->F, 24, 1));               /* detect null pivots */
    PetscCall(MatMumpsSetCntl(k->F, 3, k->null_pivot_tol)); /* relative threshold of a null pivot */
  } else {
    PetscBool set;
    char      prefix[256], name[300];
    /* CHOLMOD prints "not positive definite" itself; its errors reach PETSc's error handler anyway, and a
       rejection is logged with -info: silent unless the user asks */
    PetscCall(FactorPrefix(k, prefix, sizeof(prefix)));
    PetscCall(PetscOptionsHasName(NULL, prefix, "-mat_cholmod_print", &set));
    PetscCall(PetscSNPrintf(name, sizeof(name), "-%smat_cholmod_print", prefix));
    if (!set) PetscCall(PetscOptionsSetValue(NULL, name, "0"));
  }
  /* both packages order the matrix themselves; the natural ordering is what PETSc's interface asks for */
  PetscCall(MatGetOrdering(k->A, MATORDERINGNATURAL, &rperm, &cperm));
  PetscCall(MatFactorInfoInitialize(&info));
  PetscCall(MatCholeskyFactorSymbolic(k->F, k->A, rperm, &info));
  PetscCall(ISDestroy(&rperm));
  PetscCall(ISDestroy(&cperm));
  PetscCall(PatternOf(k->A, &k->pattern_n, &k->pattern_nnz, &k->pattern_hash));
  PetscCall(FactorNumeric(k, ok));
  PetscFunctionReturn(0);
}

/* Reuse F's symbolic factorization when A has the layout and pattern of the matrix F was analysed for,
   on every rank. */
static PetscErrorCode CanReuseSymbolic(KergsKernel k, PetscBool *reuse)
{
  PetscInt           n, nnz;
  unsigned long long h;
  PetscInt           same;

  PetscFunctionBeginUser;
  *reuse = PETSC_FALSE;
  if (!k->F) PetscFunctionReturn(0);
  PetscCall(PatternOf(k->A, &n, &nnz, &h));
  same = (n == k->pattern_n && nnz == k->pattern_nnz && h == k->pattern_hash) ? 1 : 0;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &same, 1, MPIU_INT, MPI_MIN, k->comm));
  *reuse = same ? PETSC_TRUE : PETSC_FALSE;
  PetscFunctionReturn(0);
}

/* A deterministic pseudo-random value in [-1, 1] for global index i (the same on any number of ranks). */
static PetscReal PseudoRandom(PetscInt i, unsigned long long seed)
{
  unsigned long long z = (unsigned long long)i + seed * 0x9E3779B97F4A7C15ULL;
  z                    = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z                    = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return 2.0 * (PetscReal)(z >> 11) / 9007199254740992.0 - 1.0;
}

static PetscErrorCode FillPseudoRandom(Vec v, unsigned long long seed)
{
  PetscScalar *a;
  PetscInt     lo, hi;

  PetscFunctionBeginUser;
  PetscCall(VecGetOwnershipRange(v, &lo, &hi));
  PetscCall(VecGetArray(v, &a));
  for (PetscInt i = lo; i < hi; i++) a[i - lo] = PseudoRandom(i, seed);
  PetscCall(VecRestoreArray(v, &a));
  PetscFunctionReturn(0);
}

/* yr = P xr on the kept components: yr = xr - Hr A^+ Hr^T xr (xr and yr may not alias). */
static PetscErrorCode ProjectReduced(KergsKernel k, Vec xr, Vec yr)
{
  PetscFunctionBeginUser;
  PetscCall(MatMultTranspose(k->Hr, xr, k->br));
  PetscCall(MatSolve(k->F, k->br, k->ar));
  PetscCall(MatMult(k->Hr, k->ar, yr));
  PetscCall(VecAYPX(yr, -1.0, xr));
  PetscFunctionReturn(0);
}

/* Self-check of the factorization: |Hr^T P x| / |Hr^T x| on a pseudo-random x, and for CHOLMOD (which has no
   null-pivot detection) an estimate of the condition of A from one solve, |A|_1 |A^-1 v|_1 / |v|_1. */
static PetscErrorCode CheckFactor(KergsKernel k, PetscBool cholmod)
{
  Vec       x, Px;
  PetscReal nb, nr;

  PetscFunctionBeginUser;
  k->cond_estimate = 0;
  if (cholmod) {
    PetscReal nA, nv, ny;
    PetscCall(FillPseudoRandom(k->br, 7));
    PetscCall(MatSolve(k->F, k->br, k->ar));
    PetscCall(MatNorm(k->A, NORM_1, &nA));
    PetscCall(VecNorm(k->br, NORM_1, &nv));
    PetscCall(VecNorm(k->ar, NORM_1, &ny));
    k->cond_estimate = (PetscIsInfOrNanReal(ny) || nv == 0) ? PETSC_MAX_REAL : nA * ny / nv;
  }
  PetscCall(VecDuplicate(k->xr, &x));
  PetscCall(VecDuplicate(k->xr, &Px));
  PetscCall(FillPseudoRandom(x, 11));
  PetscCall(ProjectReduced(k, x, Px));
  PetscCall(MatMultTranspose(k->Hr, x, k->br));
  PetscCall(VecNorm(k->br, NORM_2, &nb));
  PetscCall(MatMultTranspose(k->Hr, Px, k->br));
  PetscCall(VecNorm(k->br, NORM_2, &nr));
  k->check_error = (PetscIsInfOrNanReal(nr) || nb == 0) ? (nb == 0 && nr == 0 ? 0 : PETSC_MAX_REAL) : nr / nb;
  PetscCall(VecDestroy(&x));
  PetscCall(VecDestroy(&Px));
  PetscFunctionReturn(0);
}

/* The package of -kernel_solver: auto = cholmod on one rank (when PETSc has it), mumps on several. */
static PetscErrorCode ChooseSolver(KergsKernel k, const char **solver)
{
  PetscMPIInt size;
  PetscBool   isauto, ischolmod, avail = PETSC_FALSE;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(k->comm, &size));
  PetscCall(PetscStrcmp(k->solver, "auto", &isauto));
  PetscCall(PetscStrcmp(k->solver, "cholmod", &ischolmod));
  PetscCheck(!ischolmod || size == 1, k->comm, PETSC_ERR_ARG_INCOMP,
             "-kernel_solver cholmod is sequential only (%d ranks here): use -kernel_solver mumps or auto", (int)size);
  *solver = MATSOLVERMUMPS;
  if (isauto || ischolmod) {
    if (size == 1) PetscCall(MatGetFactorAvailable(k->A, MATSOLVERCHOLMOD, MAT_FACTOR_CHOLESKY, &avail));
    PetscCheck(avail || !ischolmod, k->comm, PETSC_ERR_SUP,
               "-kernel_solver cholmod: this PETSc has no CHOLMOD Cholesky for AIJ matrices; use -kernel_solver mumps");
    if (avail) *solver = MATSOLVERCHOLMOD;
  }
  PetscFunctionReturn(0);
}

/* Null pivots and factor entries. MUMPS's null-pivot count comes from the pivots of its LDL^T, which depend on
   its ordering: a null pivot polluted by rounding above the threshold goes uncounted (measured on a hypostatic
   frictionless packing: 3 of 4 found). A has at least (rows - rows of Hr) null directions, since
   rank A = rank Hr <= rows of Hr: the count is raised to that when MUMPS found fewer (logged). */
static PetscErrorCode RecordFactorStatistics(KergsKernel k, PetscBool cholmod)
{
  PetscInt nullp = 0, nnz = 0, least = PetscMax(0, k->kept_dofs - k->kept_comps);

  PetscFunctionBeginUser;
  k->nnz_known = (PetscBool)!cholmod;
  if (!cholmod) {
    PetscCall(MatMumpsGetInfog(k->F, 28, &nullp));
    PetscCall(MatMumpsGetInfog(k->F, 29, &nnz));
    if (nnz < 0) nnz = -nnz * 1000000; /* MUMPS: negative means millions */
  }
  if (nullp < least)
    PetscCall(PetscInfo(NULL,
                        "Kernel: MUMPS found %" PetscInt_FMT " null pivots, but A (%" PetscInt_FMT " rows) has rank at most %" PetscInt_FMT
                        ": counting %" PetscInt_FMT "\n",
                        nullp, k->kept_dofs, k->kept_comps, least));
  k->null_pivots = PetscMax(nullp, least);
  k->nnz_factor  = nnz;
  PetscFunctionReturn(0);
}

/* After a rejection, CHOLMOD is not tried for this many set-ups: what made A singular (rigid motions of a free
   cluster, floppy modes) tends to last, and every failed attempt costs a factorization. */
#define KERGS_KERNEL_CHOLMOD_PAUSE 10

static PetscErrorCode FallBackToMumps(KergsKernel k, const char *why)
{
  PetscBool ok;

  PetscFunctionBeginUser;
  PetscCall(PetscInfo(
      NULL, "Kernel: CHOLMOD factor of H_f H_f^T (%" PetscInt_FMT " rows) rejected (%s): MUMPS with null-pivot detection instead\n",
      k->kept_dofs, why));
  k->fell_back     = PETSC_TRUE;
  k->cholmod_pause = KERGS_KERNEL_CHOLMOD_PAUSE;
  k->fallbacks++;
  PetscCall(FactorFresh(k, MATSOLVERMUMPS, &ok));
  PetscCall(CheckFactor(k, PETSC_FALSE));
  PetscFunctionReturn(0);
}

/* Factor A (reusing the symbolic factorization when the pattern allows) and check it. CHOLMOD has no null-pivot
   detection: it is not tried when A is singular by its sizes, and its factor is rejected for MUMPS when it fails,
   when A is numerically singular (condition estimate above 1 / -kernel_null_pivot_tol) or when the projector
   misses -kernel_check_tol. A MUMPS projector that misses the check is a failure of the step (check_failed). */
static PetscErrorCode Factor(KergsKernel k)
{
  const char *solver;
  PetscBool   reuse, ok, cholmod, same;
  char        why[128];

  PetscFunctionBeginUser;
  PetscCall(ChooseSolver(k, &solver));
  k->fell_back = PETSC_FALSE;
  PetscCall(PetscStrcmp(solver, MATSOLVERCHOLMOD, &cholmod));
  if (cholmod && k->kept_dofs > k->kept_comps) {
    PetscCall(PetscInfo(NULL,
                        "Kernel: H_f H_f^T (%" PetscInt_FMT " rows) is singular by its sizes (%" PetscInt_FMT
                        " contact components): MUMPS with null-pivot detection instead of CHOLMOD\n",
                        k->kept_dofs, k->kept_comps));
    k->fell_back = PETSC_TRUE;
    k->fallbacks++;
    solver = MATSOLVERMUMPS;
  } else if (cholmod && k->cholmod_pause > 0) {
    PetscCall(PetscInfo(NULL, "Kernel: CHOLMOD paused after a rejection (%" PetscInt_FMT " more set-ups): MUMPS\n", --k->cholmod_pause));
    solver = MATSOLVERMUMPS;
  }
  {
    PetscCall(CanReuseSymbolic(k, &reuse));
    PetscCall(PetscStrcmp(k->used, solver, &same));
    if (!same) PetscCall(IsSolver(k, MATSOLVERMUMPS, &same)); /* after a fallback, MUMPS stays while the pattern lasts */
    if (reuse && same) {
      k->symbolic_reuses++;
      PetscCall(FactorNumeric(k, &ok));
    } else
      PetscCall(FactorFresh(k, solver, &ok));
    PetscCall(IsSolver(k, MATSOLVERCHOLMOD, &cholmod));
    if (ok) PetscCall(CheckFactor(k, cholmod));
    if (cholmod && (!ok || k->cond_estimate * k->null_pivot_tol > 1 || k->check_error > k->check_tol)) {
      if (!ok)
        PetscCall(PetscSNPrintf(why, sizeof(why), "not positive definite"));
      else
        PetscCall(
            PetscSNPrintf(why, sizeof(why), "condition estimate %g, projector check %g", (double)k->cond_estimate, (double)k->check_error));
      PetscCall(FallBackToMumps(k, why));
      cholmod = PETSC_FALSE;
    }
  }
  /* not an error: the step goes on with this projector, and the failure reaches the statistics (KergsKernelGetStats), where
     the solver reports it and the time loop stops with status 5 after the step (docs/running.md) */
  k->check_failed = (PetscBool) !(k->check_error <= k->check_tol);
  if (k->check_failed)
    PetscCall(PetscInfo(NULL, "Kernel: the projector from %s misses ker H_f: |H_f P x| / |H_f x| = %g > -kernel_check_tol %g\n", k->used,
                        (double)k->check_error, (double)k->check_tol));
  PetscCall(RecordFactorStatistics(k, cholmod));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* The shell Z = omega P                                                                             */

PetscErrorCode KergsKernelProject(KergsKernel k, Vec x, Vec y)
{
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  PetscCall(PetscLogEventBegin(KERGS_KernelApply, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  if (!k->Hr)
    PetscCall(VecSet(y, 0.0)); /* every contact peeled (or none): ker H_f = {0} */
  else {
    PetscCall(VecScatterBegin(k->to_reduced, x, k->xr, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(VecScatterEnd(k->to_reduced, x, k->xr, INSERT_VALUES, SCATTER_FORWARD));
    PetscCall(ProjectReduced(k, k->xr, k->yr));
    PetscCall(VecSet(y, 0.0)); /* peeled components are zero in every kernel vector */
    PetscCall(VecScatterBegin(k->to_reduced, k->yr, y, INSERT_VALUES, SCATTER_REVERSE));
    PetscCall(VecScatterEnd(k->to_reduced, k->yr, y, INSERT_VALUES, SCATTER_REVERSE));
  }
  PetscCall(PetscTime(&t1));
  k->napply++;
  k->apply_seconds += t1 - t0;
  PetscCall(PetscLogEventEnd(KERGS_KernelApply, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

static PetscErrorCode ZMult(Mat Z, Vec x, Vec y)
{
  KergsKernel k;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(Z, &k));
  PetscCall(KergsKernelProject(k, x, y));
  PetscCall(VecScale(y, k->omega));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelGetZ(KergsKernel k, Mat *Z)
{
  PetscFunctionBeginUser;
  PetscCheck(k->Z, k->comm, PETSC_ERR_ARG_WRONGSTATE, "Kernel: call KergsKernelSetUp before KergsKernelGetZ");
  *Z = k->Z;
  PetscFunctionReturn(0);
}

/* Z as a shell over contact components, with W's ncomp x ncomp block size, so that an explicit Z (nlkergs)
   can be stored by the same blocks as W. */
static PetscErrorCode CreateShell(KergsKernel k, const KernelInput *in)
{
  PetscInt n, N;

  PetscFunctionBeginUser;
  PetscCall(VecGetLocalSize(in->r, &n));
  PetscCall(VecGetSize(in->r, &N));
  PetscCall(MatCreate(k->comm, &k->Z));
  PetscCall(MatSetSizes(k->Z, n, n, N, N));
  PetscCall(MatSetBlockSize(k->Z, in->L.ncomp));
  PetscCall(MatSetType(k->Z, MATSHELL));
  PetscCall(MatShellSetContext(k->Z, k));
  PetscCall(MatSetUp(k->Z));
  PetscCall(MatShellSetOperation(k->Z, MATOP_MULT, (void (*)(void))ZMult));
  PetscCall(MatShellSetOperation(k->Z, MATOP_MULT_TRANSPOSE, (void (*)(void))ZMult));
  PetscCall(MatSetOption(k->Z, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatSetOption(k->Z, MAT_SYMMETRY_ETERNAL, PETSC_TRUE));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */

PetscErrorCode KergsKernelSetUp(KergsKernel k, KergsScene scene, KergsContacts contacts, KergsOperators ops)
{
  PetscLogDouble t0, t1;
  KernelInput    input, *in = &input;

  PetscFunctionBeginUser;
  PetscCall(GetKernelInput(scene, contacts, ops, in));
  PetscCheck(in->HfT && in->r, k->comm, PETSC_ERR_ARG_WRONGSTATE,
             "Kernel: assemble the operators (KergsOperatorsAssemble) before KergsKernelSetUp");
  PetscCall(PetscLogEventBegin(KERGS_Factor, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  PetscCall(DestroyStepObjects(k));
  k->ncomp       = in->L.ncomp;
  k->nlocal      = in->ncontacts;
  k->ncols       = in->nglobal * in->L.ncomp;
  k->nrows       = in->L.nfree;
  k->null_pivots = k->nnz_factor = 0;
  k->kept_dofs = k->kept_comps = 0;
  k->check_error = k->cond_estimate = 0;
  k->fell_back = k->check_failed = PETSC_FALSE;
  k->napply                      = 0;
  k->apply_seconds               = 0;
  k->diag_seconds                = 0;
  k->nsetups++;
  PetscCall(Eliminate(k, in));
  k->ncols -= k->inactive_contacts * k->ncomp; /* H_f over the active contacts */
  if (k->ncols - k->peeled_contacts * k->ncomp > 0) {
    PetscCall(BuildReducedOperator(k, in));
    PetscCall(Factor(k));
  } /* else nothing is left: P = 0, and the last factor is kept for a later step of its pattern */
  k->rank = k->ncomp * k->peeled_contacts + k->kept_dofs - k->null_pivots;
  PetscCall(CreateShell(k, in));
  PetscCall(PetscTime(&t1));
  k->factor_seconds = t1 - t0;
  PetscCall(PetscLogEventEnd(KERGS_Factor, 0, 0, 0, 0));
  PetscCall(PetscInfo(
      NULL,
      "Kernel: H_f %" PetscInt_FMT " x %" PetscInt_FMT ", rank %" PetscInt_FMT " (deficiency %" PetscInt_FMT ": %" PetscInt_FMT
      " DOFs of %" PetscInt_FMT " grains without contact, %" PetscInt_FMT " from %" PetscInt_FMT " peeled contacts, %" PetscInt_FMT
      " null pivots), kernel dimension %" PetscInt_FMT "; %s%s, factor entries %" PetscInt_FMT "%s, %g s\n",
      k->nrows, k->ncols, k->rank, k->nrows - k->rank, k->floating_dofs, k->floating_grains, k->deficiency_peeled, k->peeled_contacts,
      k->null_pivots, k->ncols - k->rank, k->Hr ? k->used : "no factorization", k->fell_back ? " (CHOLMOD fell back)" : "", k->nnz_factor,
      k->nnz_known || !k->Hr ? "" : " (not reported by CHOLMOD)", (double)k->factor_seconds));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Diagonal blocks of Z                                                                             */

/* Local contacts that were kept. */
static PetscErrorCode KeptLocalContacts(KergsKernel k, PetscInt *n, PetscInt **list)
{
  PetscFunctionBeginUser;
  *n = 0;
  PetscCall(PetscMalloc1(k->nlocal + 1, list));
  for (PetscInt c = 0; c < k->nlocal; c++)
    if (k->kept_offset[c] >= 0) (*list)[(*n)++] = c;
  PetscFunctionReturn(0);
}

/* Exact: Z_aa = omega (I - h_a^T A^+ h_a), h_a = the rows of Hr of contact a. Batches of -kernel_diag_batch
   contacts per rank: B = [h_a ...] (kept DOFs x columns, dense), X = A^-1 B, Y = Hr X, and the block of
   contact a is read in its own rows of Y (local) at its own columns. Collective: every rank takes part in as
   many batches as the rank with the most contacts. */
static PetscErrorCode DiagonalExact(KergsKernel k)
{
  PetscInt nc = k->ncomp, nkept, *list, nbatch, mdof, hrlo;

  PetscFunctionBeginUser;
  PetscCall(KeptLocalContacts(k, &nkept, &list));
  nbatch = (nkept + k->diag_batch - 1) / k->diag_batch;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &nbatch, 1, MPIU_INT, MPI_MAX, k->comm));
  PetscCall(MatGetLocalSize(k->A, &mdof, NULL));
  PetscCall(MatGetOwnershipRange(k->Hr, &hrlo, NULL));
  for (PetscInt b = 0; b < nbatch; b++) {
    PetscInt           first = b * k->diag_batch, cnt = PetscMax(0, PetscMin(k->diag_batch, nkept - first)), clo, lda;
    Mat                B, X, Y;
    const PetscScalar *y;

    PetscCall(MatCreateDense(k->comm, mdof, cnt * nc, PETSC_DETERMINE, PETSC_DETERMINE, NULL, &B));
    PetscCall(MatGetOwnershipRangeColumn(B, &clo, NULL));
    for (PetscInt j = 0; j < cnt; j++)
      for (PetscInt c = 0; c < nc; c++) {
        PetscInt           row = hrlo + k->kept_offset[list[first + j]] + c, col = clo + j * nc + c, ncols;
        const PetscInt    *cols;
        const PetscScalar *vals;
        PetscCall(MatGetRow(k->Hr, row, &ncols, &cols, &vals));
        for (PetscInt i = 0; i < ncols; i++) PetscCall(MatSetValue(B, cols[i], col, vals[i], INSERT_VALUES));
        PetscCall(MatRestoreRow(k->Hr, row, &ncols, &cols, &vals));
      }
    PetscCall(MatAssemblyBegin(B, MAT_FINAL_ASSEMBLY));
    PetscCall(MatAssemblyEnd(B, MAT_FINAL_ASSEMBLY));
    PetscCall(MatDuplicate(B, MAT_DO_NOT_COPY_VALUES, &X));
    PetscCall(MatMatSolve(k->F, B, X));
    PetscCall(MatMatMult(k->Hr, X, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &Y));
    PetscCall(MatDenseGetLDA(Y, &lda));
    PetscCall(MatDenseGetArrayRead(Y, &y));
    for (PetscInt j = 0; j < cnt; j++) {
      PetscInt   a = list[first + j], r0 = k->kept_offset[a];
      PetscReal *z = k->Zdiag + a * nc * nc;
      for (PetscInt c = 0; c < nc; c++)
        for (PetscInt d = 0; d < nc; d++) {
          /* h_c^T A^+ h_d, symmetrised against rounding */
          PetscReal hah =
              0.5 * (PetscRealPart(y[(r0 + c) + lda * (clo + j * nc + d)]) + PetscRealPart(y[(r0 + d) + lda * (clo + j * nc + c)]));
          z[c * nc + d] = k->omega * ((c == d ? 1.0 : 0.0) - hah);
        }
    }
    PetscCall(MatDenseRestoreArrayRead(Y, &y));
    PetscCall(MatDestroy(&Y));
    PetscCall(MatDestroy(&X));
    PetscCall(MatDestroy(&B));
  }
  PetscCall(PetscFree(list));
  PetscFunctionReturn(0);
}

/* Bound: for a column h of H_f (a row of Hr), h lies in range(A), so by Cauchy-Schwarz
   |h|^4 = (h^T A^{1/2} A^{+1/2} h)^2 <= (h^T A h)(h^T A^+ h), hence Z_cc = omega (1 - h^T A^+ h) <=
   omega (1 - |h|^4 / h^T A h). With K = Hr Hr^T: |h|^2 = K_cc and h^T A h = |Hr h|^2 = sum_j K_jc^2.
   The off-diagonal entries of the block are set to 0. */
static PetscErrorCode DiagonalBound(KergsKernel k)
{
  PetscInt nc = k->ncomp, hrlo;
  Mat      K;

  PetscFunctionBeginUser;
  PetscCall(MatMatTransposeMult(k->Hr, k->Hr, MAT_INITIAL_MATRIX, PETSC_DEFAULT, &K));
  PetscCall(MatGetOwnershipRange(k->Hr, &hrlo, NULL));
  for (PetscInt a = 0; a < k->nlocal; a++) {
    if (k->kept_offset[a] < 0) continue;
    for (PetscInt c = 0; c < nc; c++) {
      PetscInt           row = hrlo + k->kept_offset[a] + c, ncols;
      const PetscInt    *cols;
      const PetscScalar *vals;
      PetscReal          diag = 0, sumsq = 0;
      PetscCall(MatGetRow(K, row, &ncols, &cols, &vals));
      for (PetscInt i = 0; i < ncols; i++) {
        sumsq += PetscSqr(PetscRealPart(vals[i]));
        if (cols[i] == row) diag = PetscRealPart(vals[i]);
      }
      PetscCall(MatRestoreRow(K, row, &ncols, &cols, &vals));
      k->Zdiag[a * nc * nc + c * nc + c] = sumsq > 0 ? k->omega * (1.0 - diag * diag / sumsq) : k->omega;
    }
  }
  PetscCall(MatDestroy(&K));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelComputeDiagonalBlocks(KergsKernel k)
{
  PetscLogDouble t0, t1;

  PetscFunctionBeginUser;
  PetscCheck(k->Z, k->comm, PETSC_ERR_ARG_WRONGSTATE, "Kernel: call KergsKernelSetUp before KergsKernelComputeDiagonalBlocks");
  PetscCall(PetscLogEventBegin(KERGS_KernelDiag, 0, 0, 0, 0));
  PetscCall(PetscTime(&t0));
  PetscCall(PetscFree(k->Zdiag));
  PetscCall(PetscCalloc1(k->nlocal * k->ncomp * k->ncomp + 1, &k->Zdiag)); /* peeled contacts: Z_aa = 0 */
  if (k->Hr) {
    if (k->diagtype == KERGS_KERNEL_DIAG_EXACT)
      PetscCall(DiagonalExact(k));
    else
      PetscCall(DiagonalBound(k));
  }
  PetscCall(PetscTime(&t1));
  k->diag_seconds = t1 - t0;
  PetscCall(PetscLogEventEnd(KERGS_KernelDiag, 0, 0, 0, 0));
  PetscCall(PetscInfo(NULL, "Kernel: %s diagonal blocks of Z in %g s\n", KergsKernelDiags[k->diagtype], (double)k->diag_seconds));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */

PetscErrorCode KergsKernelView(KergsKernel k, PetscViewer viewer)
{
  PetscBool ascii;

  PetscFunctionBeginUser;
  PetscCall(PetscObjectTypeCompare((PetscObject)viewer, PETSCVIEWERASCII, &ascii));
  if (!ascii) PetscFunctionReturn(0);
  PetscCall(PetscViewerASCIIPrintf(viewer, "Kernel projector P = I - H_f^T (H_f H_f^T)^+ H_f, Z = omega P (omega %g)\n", (double)k->omega));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPrintf(
      viewer, "solver %s, diagonal %s (batches of %" PetscInt_FMT " contacts per rank), null pivot tolerance %g, check tolerance %g\n",
      k->solver, KergsKernelDiags[k->diagtype], k->diag_batch, (double)k->null_pivot_tol, (double)k->check_tol));
  if (k->nsetups) {
    PetscCall(PetscViewerASCIIPrintf(
        viewer, "last step: H_f %" PetscInt_FMT " x %" PetscInt_FMT ", rank %" PetscInt_FMT ", kernel dimension %" PetscInt_FMT "\n",
        k->nrows, k->ncols, k->rank, k->ncols - k->rank));
    PetscCall(PetscViewerASCIIPrintf(viewer,
                                     "row deficiency %" PetscInt_FMT " = %" PetscInt_FMT " DOFs without contact (%" PetscInt_FMT
                                     " grains) + %" PetscInt_FMT " from %" PetscInt_FMT " peeled contacts (%" PetscInt_FMT
                                     " single-contact grains before peeling) + %" PetscInt_FMT " null pivots\n",
                                     k->nrows - k->rank, k->floating_dofs, k->floating_grains, k->deficiency_peeled, k->peeled_contacts,
                                     k->single_contact_grains, k->null_pivots));
    if (k->Hr) {
      PetscCall(PetscViewerASCIIPrintf(viewer,
                                       "reduced A = Hr^T Hr: %" PetscInt_FMT " rows, Hr %" PetscInt_FMT " components; factored by %s%s\n",
                                       k->kept_dofs, k->kept_comps, k->used, k->fell_back ? " (CHOLMOD rejected)" : ""));
      if (k->nnz_known)
        PetscCall(PetscViewerASCIIPrintf(viewer, "factor entries %" PetscInt_FMT "\n", k->nnz_factor));
      else
        PetscCall(PetscViewerASCIIPrintf(viewer, "factor entries: not reported by PETSc's CHOLMOD interface\n"));
      if (k->cond_estimate > 0)
        PetscCall(PetscViewerASCIIPrintf(viewer, "projector check |H_f P x| / |H_f x| = %g, condition estimate of A %g\n",
                                         (double)k->check_error, (double)k->cond_estimate));
      else
        PetscCall(PetscViewerASCIIPrintf(viewer, "projector check |H_f P x| / |H_f x| = %g\n", (double)k->check_error));
    } else
      PetscCall(PetscViewerASCIIPrintf(viewer, "no contact left after elimination: P = 0\n"));
    PetscCall(PetscViewerASCIIPrintf(viewer, "set-up %g s, diagonal %g s, %" PetscInt_FMT " applications %g s\n", (double)k->factor_seconds,
                                     (double)k->diag_seconds, k->napply, (double)k->apply_seconds));
    PetscCall(PetscViewerASCIIPrintf(
        viewer, "%" PetscInt_FMT " set-ups, %" PetscInt_FMT " reused the symbolic factorization, %" PetscInt_FMT " CHOLMOD fallbacks\n",
        k->nsetups, k->symbolic_reuses, k->fallbacks));
  }
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelGetDiagonalBlocks(KergsKernel k, const PetscReal **Zdiag)
{
  PetscFunctionBeginUser;
  PetscCheck(k->Zdiag, k->comm, PETSC_ERR_ORDER, "KergsKernelGetDiagonalBlocks: call KergsKernelComputeDiagonalBlocks first");
  *Zdiag = k->Zdiag;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsKernelGetStats(KergsKernel k, KergsKernelStats *st)
{
  PetscFunctionBeginUser;
  st->ncols           = k->ncols;
  st->nrows           = k->nrows;
  st->rank            = k->rank;
  st->floating_grains = k->floating_grains;
  st->peeled_contacts = k->peeled_contacts;
  st->null_pivots     = k->null_pivots;
  st->nnz_factor      = k->nnz_factor;
  st->factor_seconds  = k->factor_seconds;
  st->diag_seconds    = k->diag_seconds;
  st->check_error     = k->check_error;
  st->check_tol       = k->check_tol;
  st->check_failed    = k->check_failed;
  st->package         = k->used;
  PetscFunctionReturn(0);
}
