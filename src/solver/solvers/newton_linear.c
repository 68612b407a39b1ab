/* The linear algebra of solver type "newton" (newton.c): the Jacobian J = A + B (W + sigma I) + eps I of the
   Alart-Curnier function, built on W's pattern (A, B block diagonal, one ncomp x ncomp block per contact), and the
   solves of J d = -F. One rank: PETSc's LU, J stored in W's AMD order (PresortContacts), or without friction CHOLMOD's
   Cholesky of J's rows divided by B (SymmetricRows); several ranks: J gathered
   whole up to -solver_newton_redundant_max rows, else GMRES with additive Schwarz (ChooseLinearSolver); a stale
   factorization reused by GMRES while few contacts changed piece (ReuseDirection). docs/solver.md, "Linear algebra". */
#include "newton.h"
#include <string.h>

static PetscErrorCode KernelJacobianMult(Mat, Vec, Vec); /* J_P (-solver_prox kernel), below */

/* The local (diagonal) part of a parallel matrix, or the matrix itself, and the off-process part (NULL on one rank). */
static PetscErrorCode GetParts(Mat M, PetscInt nc, Mat *Ad, Mat *Ao)
{
  PetscBool mpi;

  PetscFunctionBeginUser;
  *Ao = NULL;
  PetscCall(PetscObjectTypeCompareAny((PetscObject)M, &mpi, MATMPIAIJ, MATMPIBAIJ, ""));
  if (!mpi)
    *Ad = M;
  else if (nc > 1)
    PetscCall(MatMPIBAIJGetSeqBAIJ(M, Ad, Ao, NULL));
  else
    PetscCall(MatMPIAIJGetSeqAIJ(M, Ad, Ao, NULL));
  PetscFunctionReturn(0);
}

/* J's template: W over J's rows (the working contacts, or all), in W's AMD order when presorted. */
static Mat JacobianTemplate(const Newton *nt) { return nt->Wsorted ? nt->Wsorted : (nt->Wwork ? nt->Wwork : nt->Wfull); }

/* J's block (alpha, beta) from W's: out = B w, and on alpha's own block (own) A + sigma B + eps I added. B and A are row-major (nc x nc); w
   and out are stored as BAIJ stores a block, column by column (entry (c, e) at c + e nc). */
static inline void JacobianBlock(PetscInt nc, const PetscReal *Ba, const PetscReal *Aa, const PetscScalar *w, PetscBool own,
                                 PetscReal sigma, PetscReal eps, PetscScalar *out)
{
  if (nc == 2) { /* the 2D case, written out: most of the time goes here */
    out[0] = Ba[0] * w[0] + Ba[1] * w[1];
    out[1] = Ba[2] * w[0] + Ba[3] * w[1];
    out[2] = Ba[0] * w[2] + Ba[1] * w[3];
    out[3] = Ba[2] * w[2] + Ba[3] * w[3];
  } else
    for (PetscInt c = 0; c < nc; c++)
      for (PetscInt e = 0; e < nc; e++) {
        PetscScalar sum = 0.0;
        for (PetscInt k = 0; k < nc; k++) sum += Ba[c * nc + k] * w[k + e * nc];
        out[c + e * nc] = sum;
      }
  if (own)
    for (PetscInt c = 0; c < nc; c++) {
      for (PetscInt e = 0; e < nc; e++) out[c + e * nc] += Aa[c * nc + e] + sigma * Ba[c * nc + e];
      out[c + c * nc] += eps;
    }
}

/* Block row a of a sequential (B)AIJ matrix P of nrows block rows on W's pattern (Wpart) is B_k (nc x nc) times block row a of Wpart,
   and, where own is given, A_k + sigma B_k + eps I is also added to the row's own block, at own[a]. Row a's blocks are
   A + k stride and B + k stride, k = order[a] (or a). BAIJ stores each block column by column: entry (c, e) at
   c + e nc. Reading W and writing P in one pass spares copying W into P first. J's parts (NewtonAssembleJacobian) and
   additive Schwarz's subdomains (newton_subdomain.c) are both computed here, so that both hold the same values to the
   bit. */
PetscErrorCode NewtonScaleRows(Mat Wpart, Mat P, PetscInt nrows, PetscInt nc, const PetscReal *A, const PetscReal *B, PetscInt stride,
                               const PetscInt *order, const PetscInt *own, PetscReal sigma, PetscReal eps)
{
  const PetscInt *ia, *ja;
  PetscInt        nrow;
  PetscBool       done;
  PetscScalar    *w, *v; /* W is only read (PETSc 3.18 has no read-only access to a BAIJ array) */

  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(P, 0, PETSC_FALSE, (PetscBool)(nc > 1), &nrow, &ia, &ja, &done));
  PetscCheck(done && nrow == nrows, PETSC_COMM_SELF, PETSC_ERR_PLIB, "newton: cannot read the rows of J or of a subdomain");
  if (nc > 1) {
    PetscCall(MatSeqBAIJGetArray(Wpart, &w));
    PetscCall(MatSeqBAIJGetArray(P, &v));
  } else {
    PetscCall(MatSeqAIJGetArrayRead(Wpart, (const PetscScalar **)&w));
    PetscCall(MatSeqAIJGetArray(P, &v));
  }
  for (PetscInt a = 0; a < nrow; a++) {
    const PetscInt   k  = order ? order[a] : a;
    const PetscReal *Aa = A + k * stride, *Ba = B + k * stride;
    for (PetscInt j = ia[a]; j < ia[a + 1]; j++)
      JacobianBlock(nc, Ba, Aa, w + j * nc * nc, (PetscBool)(own && j == own[a]), sigma, eps, v + j * nc * nc);
  }
  if (nc > 1) {
    PetscCall(MatSeqBAIJRestoreArray(P, &v));
    PetscCall(MatSeqBAIJRestoreArray(Wpart, &w));
  } else {
    PetscCall(MatSeqAIJRestoreArray(P, &v));
    PetscCall(MatSeqAIJRestoreArrayRead(Wpart, (const PetscScalar **)&w));
  }
  PetscCall(MatRestoreRowIJ(P, 0, PETSC_FALSE, (PetscBool)(nc > 1), &nrow, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

/* Without friction, on one rank (nt->symmetric): J d = -F with each row of J = A + B (W + sigma I) + eps I divided by
   its B where B > 0, (A + eps) / B + W_ii + sigma on its diagonal and W_ij elsewhere, except in the columns of the
   contacts with B = 0 (the open piece, A = 1), whose rows are W_ii times the identity's: their d = -F / (A + eps) is known and
   moved to the right-hand side (SymmetricRightHandSide). A and B are nonnegative on every piece of the frictionless law
   and of its smoothing, W is positive semi-definite and eps > 0 (NewtonChoosePresorting), so J is symmetric positive definite: Cholesky
   instead of LU, the same d. T is J's template (W over J's rows, in J's order), P is J; both sequential AIJ on one
   pattern. A and B are those being assembled (Aused, Bused), which SymmetricRightHandSide reads too. *finite is false
   when a value is not: CHOLMOD stops with an error on such a J, where a failed solve should lead to a larger proximal
   term (NewtonSolveDirection). */
static PetscErrorCode SymmetricRows(Mat T, Mat P, const Newton *nt, PetscReal sigma, PetscReal eps, PetscBool *finite)
{
  const PetscInt    *ia, *ja;
  PetscInt           nrow;
  PetscBool          done;
  const PetscScalar *w;
  PetscScalar       *v;

  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(P, 0, PETSC_FALSE, PETSC_FALSE, &nrow, &ia, &ja, &done));
  PetscCheck(done && nrow == nt->nrows, PETSC_COMM_SELF, PETSC_ERR_PLIB, "newton: cannot read the rows of J");
  PetscCall(MatSeqAIJGetArrayRead(T, &w));
  PetscCall(MatSeqAIJGetArray(P, &v));
  *finite = PETSC_TRUE;
  for (PetscInt a = 0; a < nrow; a++) {
    const PetscInt  k = NewtonRowContact(nt, a);
    const PetscReal A = nt->Aused[k], B = nt->Bused[k];
    PetscCheck(!(A < 0 || B < 0 || A + B == 0), PETSC_COMM_SELF, PETSC_ERR_PLIB, "newton: a frictionless row with A %g, B %g", (double)A,
               (double)B);

    for (PetscInt j = ia[a]; j < ia[a + 1]; j++) {
      const PetscInt col = NewtonRowContact(nt, ja[j]);
      if (ja[j] == a) {
        v[j] = B > 0 ? w[j] + sigma + (A + eps) / B : 1.0 / nt->rho_nat[k]; /* W_ii: every row in one unit */
        if (PetscIsInfOrNanReal(PetscRealPart(v[j]))) *finite = PETSC_FALSE;
      } else
        v[j] = B > 0 && nt->Bused[col] > 0 ? w[j] : 0.0;
    }
  }
  PetscCall(MatSeqAIJRestoreArray(P, &v));
  PetscCall(MatSeqAIJRestoreArrayRead(T, &w));
  PetscCall(MatRestoreRowIJ(P, 0, PETSC_FALSE, PETSC_FALSE, &nrow, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

/* The right-hand side of the symmetric J (SymmetricRows), from -F on J's rows (Fs): divided by B on the rows
   with B > 0, by A + eps on the others (their d, times W_ii: those rows' diagonal, so that every row is in velocity
   units and GMRES's relative tolerance weighs them alike), and W times those d taken off the first. A, B and eps are those of
   the J last assembled, which every solve of this J uses (the stale factor's GMRES included). */
static PetscErrorCode SymmetricRightHandSide(Newton *nt)
{
  PetscScalar       *b, *z;
  const PetscScalar *t;
  PetscInt           moved = 0;

  PetscFunctionBeginUser;
  PetscCall(VecGetArray(nt->Fs, &b));
  PetscCall(VecGetArray(nt->zs, &z));
  for (PetscInt i = 0; i < nt->nrows; i++) {
    const PetscInt  k = NewtonRowContact(nt, i);
    const PetscReal B = nt->Bused[k];
    z[i]              = B > 0 ? 0.0 : b[i] / (nt->Aused[k] + nt->eps_used);
    b[i]              = B > 0 ? b[i] / B : z[i] / nt->rho_nat[k]; /* the row's diagonal W_ii times its d */
    if (z[i] != 0.0) moved++;
  }
  PetscCall(VecRestoreArray(nt->zs, &z));
  if (!moved) { /* the usual case once the open contacts carry no impulse */
    PetscCall(VecRestoreArray(nt->Fs, &b));
    PetscFunctionReturn(0);
  }
  PetscCall(MatMult(JacobianTemplate(nt), nt->zs, nt->ts));
  PetscCall(VecGetArrayRead(nt->ts, &t));
  for (PetscInt i = 0; i < nt->nrows; i++)
    if (nt->Bused[NewtonRowContact(nt, i)] > 0) b[i] -= t[i];
  PetscCall(VecRestoreArrayRead(nt->ts, &t));
  PetscCall(VecRestoreArray(nt->Fs, &b));
  PetscFunctionReturn(0);
}

/* The factorization of this step's J on one rank with kergs's LU: Cholesky by CHOLMOD when J is symmetric, else PETSc's
   LU in J's presorted (natural) order. Switched only when J's form changed (friction is the scene's, so at most once
   a run): KSPReset keeps the preconditioner's type and package. */
static PetscErrorCode ChooseFactorization(Newton *nt)
{
  PC        pc;
  PetscBool current;

  PetscFunctionBeginUser;
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, nt->symmetric ? PCCHOLESKY : PCLU, &current));
  if (current) PetscFunctionReturn(0);
  if (nt->symmetric) {
    PetscCall(PCSetType(pc, PCCHOLESKY));
    PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERCHOLMOD));
  } else {
    PetscCall(PCSetType(pc, PCLU));
    PetscCall(PCFactorSetMatSolverType(pc, MATSOLVERPETSC));
    PetscCall(PCFactorSetMatOrderingType(pc, MATORDERINGNATURAL));
  }
  PetscCall(PCSetFromOptions(pc)); /* -solver_pc_factor_* options, for the new factorization */
  PetscFunctionReturn(0);
}

/* Position of each block row's own block in a sequential (B)AIJ matrix whose row a's own block is in column a (J's
   diagonal part, a subdomain's matrix). */
PetscErrorCode NewtonLocateOwnBlocks(Mat M, PetscInt nc, PetscInt *own)
{
  const PetscInt *ia, *ja;
  PetscInt        nrow;
  PetscBool       done;

  PetscFunctionBeginUser;
  PetscCall(MatGetRowIJ(M, 0, PETSC_FALSE, (PetscBool)(nc > 1), &nrow, &ia, &ja, &done));
  PetscCheck(done, PETSC_COMM_SELF, PETSC_ERR_PLIB, "newton: cannot read the rows of J or of a subdomain");
  for (PetscInt a = 0; a < nrow; a++) {
    own[a] = -1;
    for (PetscInt j = ia[a]; j < ia[a + 1]; j++)
      if (ja[j] == a) own[a] = j;
    PetscCheck(own[a] >= 0, PETSC_COMM_SELF, PETSC_ERR_PLIB, "newton: the own block of row %" PetscInt_FMT " is not stored", a);
  }
  PetscCall(MatRestoreRowIJ(M, 0, PETSC_FALSE, (PetscBool)(nc > 1), &nrow, &ia, &ja, &done));
  PetscFunctionReturn(0);
}

/* The local contacts whose Jacobian blocks (A, B) differ from A0, B0. */
static PetscInt ChangedBlocks(const Newton *nt, PetscInt n, PetscInt nc, const PetscReal *A0, const PetscReal *B0)
{
  const size_t bytes   = (size_t)nc * nc * sizeof(PetscReal);
  PetscInt     changed = 0;

  for (PetscInt a = 0; a < n; a++)
    if (memcmp(nt->A + a * nc * nc, A0 + a * nc * nc, bytes) || memcmp(nt->B + a * nc * nc, B0 + a * nc * nc, bytes)) changed++;
  return changed;
}

/* J = A + B (W + sigma I) + eps I, unless the contact states (A, B) and sigma are those of the last Jacobian: F is
   piecewise linear, so once the states settle J stays the same and its factorization is reused (the Newton step then
   costs one solve). */
PetscErrorCode NewtonAssembleJacobian(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc, PetscReal eps, PetscReal sigma)
{
  Mat      Ad, Ao, Wd, Wo;
  PetscInt changed = (PetscInt)(sigma != nt->sigma_used || ChangedBlocks(nt, n, nc, nt->Aused, nt->Bused) > 0);

  PetscFunctionBeginUser;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &changed, 1, MPIU_INT, MPI_MAX, s->comm));
  if (!changed) PetscFunctionReturn(0);
  PetscCall(PetscArraycpy(nt->Aused, nt->A, n * nc * nc));
  PetscCall(PetscArraycpy(nt->Bused, nt->B, n * nc * nc));
  nt->sigma_used = sigma;
  nt->eps_used   = eps;
  nt->jacobians++;
  nt->stale = PETSC_TRUE;
  PetscCall(GetParts(JacobianTemplate(nt), nc, &Wd, &Wo));
  PetscCall(GetParts(nt->J, nc, &Ad, &Ao));
  if (nt->symmetric)
    PetscCall(SymmetricRows(Wd, Ad, nt, sigma, eps, &nt->finite));
  else {
    PetscCall(NewtonScaleRows(Wd, Ad, nt->nrows, nc, nt->A, nt->B, nc * nc, nt->order, nt->diagblock, sigma, eps));
    if (Ao) PetscCall(NewtonScaleRows(Wo, Ao, nt->nrows, nc, nt->A, nt->B, nc * nc, nt->order, NULL, 0.0, 0.0));
  }
  /* values changed through the arrays: assembling again tells PETSc (and the factorization) that J changed */
  PetscCall(MatAssemblyBegin(nt->J, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(nt->J, MAT_FINAL_ASSEMBLY));
  PetscCall(NewtonSubdomainSetBlocks(nt, nc));
  PetscFunctionReturn(0);
}

/* MUMPS's null-pivot detection (ICNTL(24) = 1): a singular J (hyperstatic stick networks) gets a solution of its
   consistent part instead of a failed factorization. Set on this step's factor before it is computed; an option
   -solver_mat_mumps_icntl_24 given by the user still wins (read at the factorization). */
static PetscErrorCode EnableNullPivots(Newton *nt)
{
  PC            pc;
  Mat           F;
  MatSolverType type;
  PetscBool     mumps;

  PetscFunctionBeginUser;
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCLU, &mumps));
  if (!mumps) PetscFunctionReturn(0);
  PetscCall(PCFactorGetMatSolverType(pc, &type));
  PetscCall(PetscStrcmp(type, MATSOLVERMUMPS, &mumps));
  if (!mumps) PetscFunctionReturn(0);
  PetscCall(PCFactorSetUpMatSolverType(pc));
  PetscCall(PCFactorGetMatrix(pc, &F));
  PetscCall(MatMumpsSetIcntl(F, 24, 1));
  PetscFunctionReturn(0);
}

/* The default linear solver on several ranks, chosen each step from J's size unless -solver_pc_type was given:
   - up to -solver_newton_redundant_max rows, J gathered whole on every rank and factored there by PETSc's LU with
     AMD (PCREDUNDANT): exact, and as fast as one rank. MUMPS spent about 12 ms in every factorization of
     confine500's J, where PETSc's LU takes well under one, and Newton factors up to 250 Jacobians a step; block
     Jacobi took about 90 GMRES iterations per Newton step there, additive Schwarz about 30 (the network of forces
     crosses the cut).
   - above, GMRES preconditioned by additive Schwarz with an overlap of one layer, one subdomain per rank factored by
     LU with AMD (ConfigureSubdomainSolvers): nothing of the size of the whole J on one rank; faster than the
     gathered LU and than block Jacobi (overlap 0) from 5,000 disks on (docs/solver.md, "Linear algebra"). Its
     preconditioning matrix is then a shell whose subdomain matrices are computed from W's (NewtonSubdomainsFromW,
     newton_subdomain.c); J stays the operator.
   -solver_redundant_* options, read last, win; the subdomain solvers are chosen by ConfigureSubdomainSolvers. */
static PetscErrorCode ChooseLinearSolver(KergsSolver s, Newton *nt)
{
  PC          pc, subpc;
  KSP         inner;
  PetscInt    rows;
  PetscMPIInt size;
  PetscBool   from_w;

  PetscFunctionBeginUser;
  nt->configure_subs = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  if (size == 1 || nt->user_pc) PetscFunctionReturn(0);
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(MatGetSize(nt->J, &rows, NULL));
  if (rows <= nt->redundant_max) {
    PetscCall(KSPSetType(nt->ksp, KSPPREONLY));
    PetscCall(PCSetType(pc, PCREDUNDANT));
    PetscCall(PCRedundantGetKSP(pc, &inner));
    PetscCall(KSPGetPC(inner, &subpc));
    PetscCall(PCSetType(subpc, PCLU));
    PetscCall(PCFactorSetMatSolverType(subpc, MATSOLVERPETSC));
    PetscCall(PCFactorSetMatOrderingType(subpc, MATORDERINGAMD));
    PetscCall(KSPSetFromOptions(inner));
    PetscFunctionReturn(0);
  }
  PetscCall(KSPSetType(nt->ksp, KSPGMRES));
  /* an inexact Newton direction: 1e-3 relative, not 1e-6, took the same Newton steps on the 100,000-disk strip, biaxial
   100k and biaxial 20k with 40-60 % of the GMRES iterations, a few more on pressure20k (184 against 164) and confine500
   (453 against 409) with half of them, and less time on all five (docs/solver.md) */
  PetscCall(KSPSetTolerances(nt->ksp, 1e-3, PETSC_DEFAULT, PETSC_DEFAULT, 200));
  PetscCall(NewtonSubdomainsFromW(nt, &from_w));
  if (from_w) { /* J stays the operator; the subdomains come from W's (newton_subdomain.c) */
    PetscCall(NewtonSubdomainCreateSource(nt, JacobianTemplate(nt), &nt->Pschwarz));
    PetscCall(KSPSetOperators(nt->ksp, nt->J, nt->Pschwarz));
  }
  PetscCall(PCSetType(pc, PCASM));
  PetscCall(PCASMSetOverlap(pc, 1));
  PetscCall(KSPSetFromOptions(nt->ksp)); /* -solver_ksp_rtol, -solver_pc_asm_overlap and the like */
  nt->configure_subs = PETSC_TRUE;       /* ConfigureSubdomainSolvers, at the first solve */
  PetscFunctionReturn(0);
}

/* The subdomain solvers of additive Schwarz exist once the KSP is set up: LU with AMD on each, chosen at the step's
   first Newton solve, once J holds its first values (set up at the step's set-up, they would first factor the
   subdomains of J's initial copy of W, singular: a wasted factorization, which fails). -solver_sub_* options, read
   last, win. */
static PetscErrorCode ConfigureSubdomainSolvers(Newton *nt)
{
  PC       pc, subpc;
  KSP     *sub;
  PetscInt nblocks;

  PetscFunctionBeginUser;
  if (!nt->configure_subs) PetscFunctionReturn(0);
  nt->configure_subs = PETSC_FALSE;
  PetscCall(NewtonChooseSortedSubdomains(nt)); /* again: an option of the subdomain solvers may be read only now */
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(KSPSetUp(nt->ksp));
  PetscCall(PCASMGetSubKSP(pc, &nblocks, NULL, &sub));
  for (PetscInt b = 0; b < nblocks; b++) {
    PetscCall(KSPSetType(sub[b], KSPPREONLY));
    PetscCall(KSPGetPC(sub[b], &subpc));
    if (nt->sorted_subdomains)
      PetscCall(NewtonSubdomainSetSortedLU(subpc)); /* LU with AMD, in the natural-ordering kernel */
    else {
      PetscCall(PCSetType(subpc, PCLU));
      PetscCall(PCFactorSetMatOrderingType(subpc, MATORDERINGAMD));
    }
    PetscCall(KSPSetFromOptions(sub[b]));
  }
  PetscFunctionReturn(0);
}

/* On one rank, with kergs's own LU (PETSc's LU through KSPPREONLY, its ordering not chosen by
   -solver_pc_factor_mat_ordering_type, no -solver_pc_type), J is built with its block rows and columns already in
   W's AMD order and factored with the natural ordering, instead of handing PETSc's LU the AMD ordering to apply: W
   is permuted once per step (its pattern, hence the ordering, is the step's), and -F and d once per Newton step. Same
   factors, same iterates up to rounding; PETSc's kernel for a permuted 2 x 2-block matrix copies and zeroes every
   block through a library call, its natural-ordering kernel does not: 12.3 ms per factorization of pressure20k's J
   instead of 15.1. */
PetscErrorCode NewtonChoosePresorting(KergsSolver s, Newton *nt)
{
  PetscMPIInt   size;
  PC            pc;
  KSPType       ktype;
  PCType        ptype;
  MatSolverType stype;
  const char   *prefix;
  PetscBool     preonly, lu, petsc, chosen, package;

  PetscFunctionBeginUser;
  nt->presort     = PETSC_FALSE;
  nt->cholesky_ok = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCall(KSPGetOptionsPrefix(nt->ksp, &prefix));
  PetscCall(PetscOptionsHasName(NULL, prefix, "-pc_factor_mat_ordering_type", &chosen));
  if (size > 1 || nt->user_pc || chosen || nt->prox == NEWTON_PROX_KERNEL) PetscFunctionReturn(0); /* J_P's MatMult uses J */
  PetscCall(KSPGetType(nt->ksp, &ktype));
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(PCGetType(pc, &ptype));
  PetscCall(PCFactorGetMatSolverType(pc, &stype));
  PetscCall(PetscStrcmp(ktype, KSPPREONLY, &preonly));
  PetscCall(PetscStrcmp(ptype, PCLU, &lu));
  PetscCall(PetscStrcmp(stype, MATSOLVERPETSC, &petsc));
  PetscCall(PetscOptionsHasName(NULL, prefix, "-pc_factor_mat_solver_type", &package));
  if (!package && !lu) { /* kergs's own Cholesky of the last step's symmetric J (ChooseFactorization), options read again */
    PetscBool cholesky, cholmod;
    PetscCall(PetscStrcmp(ptype, PCCHOLESKY, &cholesky));
    PetscCall(PetscStrcmp(stype, MATSOLVERCHOLMOD, &cholmod));
    lu = petsc = (PetscBool)(cholesky && cholmod);
  }
  nt->presort = (PetscBool)(preonly && lu && petsc);
  /* J is positive definite through the shift s > 0 (sigma may be 0: -solver_prox none, or the smoothing phase with
     -solver_newton_smoothing_kappa 0), and CHOLMOD stops with an error, not a reason, on a matrix that is not */
  nt->cholesky_ok = (PetscBool)(nt->presort && nt->cholesky && !package && nt->shift > 0);
  PetscFunctionReturn(0);
}

/* On several ranks the subdomains of kergs's additive Schwarz are factored the same way (newton_subdomain.c), unless
   -solver_pc_type, any option of the subdomain solvers (-solver_sub_*) or -solver_pc_asm_sub_mat_type was given: the
   user then chooses them, as before. Decided when the options are read, and again each step when the subdomain
   solvers are chosen (ConfigureSubdomainSolvers). */
PetscErrorCode NewtonChooseSortedSubdomains(Newton *nt)
{
  PetscMPIInt size;
  const char *prefix;
  char       *all, sub[256], mattype[256], *found, *found_type;

  PetscFunctionBeginUser;
  nt->sorted_subdomains = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_size(PetscObjectComm((PetscObject)nt->ksp), &size));
  if (size == 1 || nt->user_pc) PetscFunctionReturn(0);
  PetscCall(KSPGetOptionsPrefix(nt->ksp, &prefix));
  PetscCall(PetscSNPrintf(sub, sizeof(sub), "-%ssub_", prefix ? prefix : ""));
  PetscCall(PetscSNPrintf(mattype, sizeof(mattype), "-%spc_asm_sub_mat_type", prefix ? prefix : ""));
  PetscCall(PetscOptionsGetAll(NULL, &all));
  PetscCall(PetscStrstr(all, sub, &found));
  PetscCall(PetscStrstr(all, mattype, &found_type));
  nt->sorted_subdomains = (PetscBool)(!found && !found_type);
  PetscCall(PetscFree(all));
  PetscFunctionReturn(0);
}

/* J's rows. Without a working set, every local contact. With one (-solver_newton_working_set, newton_working.c), the
   contacts marked in_J: when some contact is left out on any rank, W over J's contacts (MatCreateSubMatrix, its rows
   in the contacts' order) becomes J's template and order[i] names J's row i. */
static PetscErrorCode SelectRows(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc)
{
  PetscInt m = 0, left_out, rstart, *blocks;
  IS       working;

  PetscFunctionBeginUser;
  nt->nrows = n;
  if (!nt->working_set) PetscFunctionReturn(0);
  for (PetscInt a = 0; a < n; a++)
    if (nt->in_J[a]) m++;
  left_out = n - m;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &left_out, 1, MPIU_INT, MPI_SUM, s->comm));
  if (left_out == 0) PetscFunctionReturn(0);
  PetscCall(MatGetOwnershipRange(nt->Wfull, &rstart, NULL));
  PetscCall(PetscMalloc1(m + 1, &nt->order)); /* never NULL: every rank, J rows or not, takes the path of a mapped J */
  PetscCall(PetscMalloc1(m, &blocks));
  m = 0;
  for (PetscInt a = 0; a < n; a++)
    if (nt->in_J[a]) {
      nt->order[m] = a;
      blocks[m++]  = rstart / nc + a;
    }
  PetscCall(ISCreateBlock(s->comm, nc, m, blocks, PETSC_OWN_POINTER, &working));
  PetscCall(MatCreateSubMatrix(nt->Wfull, working, working, MAT_INITIAL_MATRIX, &nt->Wwork));
  PetscCall(ISDestroy(&working));
  nt->nrows = m;
  PetscFunctionReturn(0);
}

/* One rank: J's template (W, or W over the working contacts) permuted into its AMD order, and order[] composed with it. */
static PetscErrorCode PresortContacts(Newton *nt, PetscInt nc)
{
  IS              rows, cols, points;
  const PetscInt *idx;
  PetscInt        m, *order;
  Mat             T = JacobianTemplate(nt); /* W, or W over the working contacts: not yet sorted */

  PetscFunctionBeginUser;
  if (!nt->presort || nt->symmetric || nt->nrows == 0) PetscFunctionReturn(0); /* CHOLMOD orders J itself */
  PetscCall(MatGetOrdering(T, MATORDERINGAMD, &rows, &cols));
  PetscCall(ISGetLocalSize(rows, &m));
  PetscCheck(m == nt->nrows, PETSC_COMM_SELF, PETSC_ERR_PLIB,
             "newton: the ordering of J's template has %" PetscInt_FMT " entries for %" PetscInt_FMT " rows of J", m, nt->nrows);
  PetscCall(PetscMalloc1(m, &order));
  PetscCall(ISGetIndices(rows, &idx));
  for (PetscInt i = 0; i < m; i++) order[i] = NewtonRowContact(nt, idx[i]);
  PetscCall(ISCreateBlock(PETSC_COMM_SELF, nc, m, idx, PETSC_COPY_VALUES, &points));
  PetscCall(ISRestoreIndices(rows, &idx));
  PetscCall(PetscFree(nt->order));
  nt->order = order;
  PetscCall(MatPermute(T, points, points, &nt->Wsorted)); /* Wsorted(i, j) = T(i', j'), i' = the AMD order's i-th row, by blocks */
  PetscCall(MatDestroy(&nt->Wwork));                      /* Wsorted is the template now */
  PetscCall(ISDestroy(&points));
  PetscCall(ISDestroy(&rows));
  PetscCall(ISDestroy(&cols));
  PetscFunctionReturn(0);
}

/* The last step's subdomain factors, before the KSP is reset for this step's J: KSPReset leaves them to the sorted
   LU (PCSHELL has no reset in PETSc 3.18), which would keep them through the step's detection and assembly. */
static PetscErrorCode ReleaseSubdomainFactors(Newton *nt)
{
  PC        pc;
  KSP      *sub;
  PetscInt  nblocks;
  PetscBool schwarz;

  PetscFunctionBeginUser;
  if (!nt->sorted_subdomains || !nt->factored) PetscFunctionReturn(0);
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCASM, &schwarz));
  if (!schwarz) PetscFunctionReturn(0);
  PetscCall(PCASMGetSubKSP(pc, &nblocks, NULL, &sub));
  for (PetscInt b = 0; b < nblocks; b++) {
    PC subpc;
    PetscCall(KSPGetPC(sub[b], &subpc));
    PetscCall(NewtonSubdomainReleaseSortedLU(subpc));
  }
  PetscFunctionReturn(0);
}

/* The step's (or the working set's) J, what was built with it, and the linear solvers' hold on it (factors included). */
PetscErrorCode NewtonDestroyJacobian(Newton *nt)
{
  PetscFunctionBeginUser;
  PetscCall(ReleaseSubdomainFactors(nt));
  PetscCall(KSPReset(nt->ksp));
  PetscCall(KSPReset(nt->kreuse));
  if (nt->kprox) PetscCall(KSPReset(nt->kprox));
  nt->factored = PETSC_FALSE;
  PetscCall(MatDestroy(&nt->Jprox));
  PetscCall(VecDestroy(&nt->kx));
  PetscCall(VecDestroy(&nt->kpx));
  PetscCall(MatDestroy(&nt->Wsorted));
  PetscCall(MatDestroy(&nt->Wwork));
  PetscCall(PetscFree(nt->order));
  PetscCall(VecDestroy(&nt->Fs));
  PetscCall(VecDestroy(&nt->ds));
  PetscCall(VecDestroy(&nt->zs));
  PetscCall(VecDestroy(&nt->ts));
  PetscCall(MatDestroy(&nt->Pschwarz));
  PetscCall(VecDestroy(&nt->row_AB));
  PetscCall(MatDestroy(&nt->J));
  PetscFunctionReturn(0);
}

/* The step's Jacobian and linear solver, after NewtonDestroyJacobian has released the last ones: J's rows chosen
   (SelectRows), W over them presorted (one rank, PresortContacts), J created on its pattern, the position of every
   diagonal block, and the KSPs given J, then the linear solver chosen for its size (ChooseLinearSolver). */
PetscErrorCode NewtonSetUpJacobian(KergsSolver s, Newton *nt, PetscInt n, PetscInt nc)
{
  Mat Ad, Ao;

  PetscFunctionBeginUser;
  nt->symmetric = (PetscBool)(nt->cholesky_ok && nc == 1);
  nt->finite    = PETSC_TRUE;
  PetscCall(SelectRows(s, nt, n, nc));
  PetscCall(PresortContacts(nt, nc));
  PetscCall(MatDuplicate(JacobianTemplate(nt), MAT_COPY_VALUES, &nt->J));
  if (nt->order || nt->symmetric) PetscCall(MatCreateVecs(nt->J, &nt->ds, &nt->Fs));
  if (nt->symmetric) PetscCall(MatCreateVecs(nt->J, &nt->zs, &nt->ts));
  if (nt->presort) PetscCall(ChooseFactorization(nt)); /* kergs's own factorization: LU, or Cholesky of the symmetric form */
  PetscCall(GetParts(nt->J, nc, &Ad, &Ao));
  PetscCall(NewtonLocateOwnBlocks(Ad, nc, nt->diagblock));
  nt->sigma_used = -1.0;
  PetscCall(KSPSetOperators(nt->ksp, nt->J, nt->J)); /* reset by NewtonDestroyJacobian: J's sizes and pattern are new */
  PetscCall(KSPSetOperators(nt->kreuse, nt->J, nt->J));
  nt->stale = PETSC_FALSE;
  PetscCall(ChooseLinearSolver(s, nt));
  PetscCall(EnableNullPivots(nt));
  if (nt->prox == NEWTON_PROX_KERNEL) { /* J_P, a shell on J's layout */
    PetscInt m, N;
    PetscCall(MatGetLocalSize(nt->J, &m, NULL));
    PetscCall(MatGetSize(nt->J, &N, NULL));
    PetscCall(MatCreateShell(s->comm, m, m, N, N, nt, &nt->Jprox));
    PetscCall(MatShellSetOperation(nt->Jprox, MATOP_MULT, (void (*)(void))KernelJacobianMult));
    PetscCall(MatCreateVecs(nt->J, &nt->kx, &nt->kpx));
    PetscCall(KSPSetOperators(nt->kprox, nt->Jprox, nt->Jprox));
  }
  PetscFunctionReturn(0);
}

/* The preconditioner of the reuse solver: the factorization (or block factorizations) last computed by ksp, applied to
   a J that has changed since. Reuse is set on ksp's PC so that applying it does not factor again. */
static PetscErrorCode ApplyStaleFactor(PC pc, Vec x, Vec y)
{
  Newton *nt;
  PC      main;

  PetscFunctionBeginUser;
  PetscCall(PCShellGetContext(pc, &nt));
  PetscCall(KSPGetPC(nt->ksp, &main));
  PetscCall(PCSetReusePreconditioner(main, PETSC_TRUE));
  PetscCall(PCApply(main, x, y));
  PetscFunctionReturn(0);
}

/* d = J^-1 (-F) by `ksp` (whose operator is J, or J_P on J's rows), counting its iterations. */
PetscErrorCode NewtonSolveSystem(Newton *nt, KSP ksp, KSPConvergedReason *reason)
{
  PetscInt its;

  PetscFunctionBeginUser;
  if (nt->order || nt->symmetric) { /* J's rows are order[]'s contacts (W's AMD order, the working set): -F into them, d back */
    PetscInt           n, nc, local;
    const PetscScalar *f, *xs;
    PetscScalar       *bs, *x;

    PetscCall(MatGetBlockSize(nt->J, &nc)); /* components per contact */
    PetscCall(VecGetLocalSize(nt->F, &local));
    n = nt->nrows;
    if (n * nc < local) { /* a contact outside J has F = r (the identity row): d = -F */
      PetscCall(VecCopy(nt->F, nt->d));
      PetscCall(VecScale(nt->d, -1.0));
    }
    PetscCall(VecGetArrayRead(nt->F, &f));
    PetscCall(VecGetArray(nt->Fs, &bs));
    for (PetscInt i = 0; i < n; i++)
      for (PetscInt c = 0; c < nc; c++) bs[i * nc + c] = -f[NewtonRowContact(nt, i) * nc + c];
    PetscCall(VecRestoreArray(nt->Fs, &bs));
    PetscCall(VecRestoreArrayRead(nt->F, &f));
    if (nt->symmetric) PetscCall(SymmetricRightHandSide(nt));
    PetscCall(KSPSolve(ksp, nt->Fs, nt->ds));
    PetscCall(VecGetArrayRead(nt->ds, &xs));
    PetscCall(VecGetArray(nt->d, &x));
    for (PetscInt i = 0; i < n; i++)
      for (PetscInt c = 0; c < nc; c++) x[NewtonRowContact(nt, i) * nc + c] = xs[i * nc + c];
    PetscCall(VecRestoreArray(nt->d, &x));
    PetscCall(VecRestoreArrayRead(nt->ds, &xs));
  } else {
    PetscCall(VecScale(nt->F, -1.0));
    PetscCall(KSPSolve(ksp, nt->F, nt->d));
    PetscCall(VecScale(nt->F, -1.0));
  }
  PetscCall(KSPGetConvergedReason(ksp, reason));
  PetscCall(KSPGetIterationNumber(ksp, &its));
  nt->linear_its += its;
  PetscFunctionReturn(0);
}

/* J d = -F with the factorization of an earlier J of this step. With sigma unchanged, J changes between Newton steps
   only in the rows of the contacts that changed piece: a low-rank change, which GMRES absorbs in about one iteration
   per changed row (two in J's symmetric form: a row and its column), each costing one triangular solve where a
   factorization costs far more. When ksp solves directly (KSPPREONLY: LU or Cholesky, or LU gathered by PCREDUNDANT), by at most
   -solver_newton_reuse_its GMRES iterations preconditioned by that factorization (kreuse); when ksp is kergs's GMRES with additive Schwarz
   (several ranks), by ksp with its preconditioner kept, to ksp's own tolerance (a Krylov method chosen by option sets up every changed J).
   Tried only when few contacts changed. *solved is false when it did not converge: then J is factored again. */
static PetscErrorCode ReuseDirection(Newton *nt, PetscInt n, PetscInt nc, PetscBool *solved)
{
  KSPConvergedReason reason;
  PetscInt           changed;
  PetscBool          direct;
  PC                 pc;

  PetscFunctionBeginUser;
  *solved = PETSC_FALSE;
  if (nt->prox == NEWTON_PROX_KERNEL || nt->reuse_its <= 0 || !nt->factored || !nt->stale || nt->sigma_used != nt->sigma_fact)
    PetscFunctionReturn(0);
  /* GMRES needs about one iteration per changed block row: try only when few changed */
  changed = ChangedBlocks(nt, n, nc, nt->Afact, nt->Bfact);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &changed, 1, MPIU_INT, MPI_SUM, PetscObjectComm((PetscObject)nt->ksp)));
  if ((nt->symmetric ? 4 : 2) * changed > nt->reuse_its) PetscFunctionReturn(0); /* symmetric: a row and its column */
  PetscCall(PetscObjectTypeCompare((PetscObject)nt->ksp, KSPPREONLY, &direct));
  if (direct)
    PetscCall(NewtonSolveSystem(nt, nt->kreuse, &reason));
  else {
    PetscBool schwarz;
    PetscCall(KSPGetPC(nt->ksp, &pc));
    PetscCall(PetscObjectTypeCompare((PetscObject)pc, PCASM, &schwarz));
    if (!schwarz || nt->user_pc) PetscFunctionReturn(0); /* a Krylov method chosen by option: every changed J is set up */
    PetscCall(PCSetReusePreconditioner(pc, PETSC_TRUE));
    PetscCall(PCSetFailedReason(pc, PC_NOERROR));
    PetscCall(NewtonSolveSystem(nt, nt->ksp, &reason));
  }
  *solved = (PetscBool)(reason > 0);
  if (*solved) nt->reused++;
  PetscFunctionReturn(0);
}

/* Solve J d = -F: with the last factorization while it serves (ReuseDirection), else by ksp, which factors J again. A
   failed solve (a Krylov method on an ill-conditioned J, a singular factorization) is not an error: the inner Newton
   stops and the outer iteration retries with a larger proximal term, which conditions J better. */
/* J_P x = A x + B (W x + sigma P x) + shift x = J x - sigma B (x - P x), J = A + B (W + sigma I) + shift I as assembled
   (-solver_prox kernel). */
static PetscErrorCode KernelJacobianMult(Mat M, Vec x, Vec y)
{
  Newton            *nt;
  PetscInt           n, nc;
  const PetscScalar *xl, *pl;
  PetscScalar       *yl;

  PetscFunctionBeginUser;
  PetscCall(MatShellGetContext(M, &nt));
  PetscCall(MatGetBlockSize(nt->J, &nc));
  PetscCall(VecGetLocalSize(x, &n));
  n /= nc;
  PetscCall(MatMult(nt->J, x, y));
  PetscCall(KergsKernelProject(nt->kernel, x, nt->kpx));
  PetscCall(VecGetArrayRead(x, &xl));
  PetscCall(VecGetArrayRead(nt->kpx, &pl));
  PetscCall(VecGetArray(y, &yl));
  for (PetscInt a = 0; a < n; a++) {
    const PetscReal *Ba = nt->Bused + a * nc * nc;
    for (PetscInt c = 0; c < nc; c++)
      for (PetscInt e = 0; e < nc; e++) yl[a * nc + c] -= nt->sigma * Ba[c * nc + e] * (xl[a * nc + e] - pl[a * nc + e]);
  }
  PetscCall(VecRestoreArray(y, &yl));
  PetscCall(VecRestoreArrayRead(nt->kpx, &pl));
  PetscCall(VecRestoreArrayRead(x, &xl));
  PetscFunctionReturn(0);
}

/* Before ksp factors J (again): its preconditioner is to be set up anew, without the failure of an earlier set-up
   (additive Schwarz keeps a subdomain's failed factorization as its own failure through later set-ups, PETSc 3.18:
   without this, one failed solve would fail every later one, however good J), and the subdomain solvers chosen. */
static PetscErrorCode PrepareFactorization(Newton *nt, PC *pc)
{
  PetscFunctionBeginUser;
  PetscCall(KSPGetPC(nt->ksp, pc));
  PetscCall(PCSetReusePreconditioner(*pc, PETSC_FALSE));
  PetscCall(PCSetFailedReason(*pc, PC_NOERROR));
  if (nt->stale || !nt->factored) nt->factorizations++;
  PetscCall(ConfigureSubdomainSolvers(nt));
  PetscFunctionReturn(0);
}

/* -solver_prox kernel: J_P d = -F by GMRES (kprox), preconditioned by the factorization of J = A + B (W + sigma I) +
   shift I, the identity term's Jacobian at the same sigma: the two agree on ker W and on the stiff modes of W's range,
   and differ on its soft modes (eigenvalues lambda of W well below sigma), where the preconditioned operator has
   eigenvalues near lambda / (lambda + sigma); GMRES needs 4 to 5 iterations per Newton step on confine500. (The
   factorization of J with the smallest sigma, nearly singular on ker W, needed hundreds and stalled the outer
   iterations.) J is factored again when it changed. */
static PetscErrorCode KernelDirection(Newton *nt, KSPConvergedReason *reason)
{
  PC pc;

  PetscFunctionBeginUser;
  PetscCall(PrepareFactorization(nt, &pc));
  PetscCall(KSPSetUp(nt->ksp));
  PetscCall(PCSetUp(pc)); /* KSPSetUp does not set the PC up again once the KSP is set up; PCSetUp factors J when it changed */
  nt->factored = PETSC_TRUE;
  nt->stale    = PETSC_FALSE;
  PetscCall(NewtonSolveSystem(nt, nt->kprox, reason)); /* J in the contacts' order: no presort with the kernel term */
  PetscFunctionReturn(0);
}

PetscErrorCode NewtonSolveDirection(Newton *nt, PetscInt n, PetscInt nc, PetscBool *solved)
{
  KSPConvergedReason reason;
  PetscLogDouble     t0, t1;
  PC                 pc;

  PetscFunctionBeginUser;
  PetscCall(PetscTime(&t0));
  if (nt->prox == NEWTON_PROX_KERNEL && nt->sigma > 0) {
    PetscCall(KernelDirection(nt, &reason));
    *solved = (PetscBool)(reason > 0);
    if (!*solved) nt->failed_linear++;
  } else if (nt->symmetric && !nt->finite) {
    *solved = PETSC_FALSE;
    nt->failed_linear++;
    PetscCall(PetscInfo(NULL, "newton: J has a value that is not finite: a larger proximal term next\n"));
  } else {
    PetscCall(ReuseDirection(nt, n, nc, solved));
    if (!*solved) {
      PetscCall(PrepareFactorization(nt, &pc));
      PetscCall(NewtonSolveSystem(nt, nt->ksp, &reason));
      nt->factored   = PETSC_TRUE;
      nt->stale      = PETSC_FALSE;
      nt->sigma_fact = nt->sigma_used;
      PetscCall(PetscArraycpy(nt->Afact, nt->Aused, n * nc * nc));
      PetscCall(PetscArraycpy(nt->Bfact, nt->Bused, n * nc * nc));
      *solved = (PetscBool)(reason >= 0);
      if (!*solved) {
        nt->failed_linear++;
        PetscCall(PetscInfo(NULL, "newton: the linear solve of a Newton step failed (%s): a larger proximal term next\n",
                            KSPConvergedReasons[reason]));
      }
    }
  }
  PetscCall(PetscTime(&t1));
  nt->linear_seconds += t1 - t0;
  PetscFunctionReturn(0);
}

/* GMRES on the unpreconditioned residual, preconditioned on the right by ksp's factorization as it stands
   (ApplyStaleFactor); a failed solve is not an error. */
static PetscErrorCode CreateFactorPreconditionedGMRES(KergsSolver s, Newton *nt, const char *inner, const char *name, KSP *ksp)
{
  PC   pc;
  char prefix[256];

  PetscFunctionBeginUser;
  PetscCall(KergsSolverInnerPrefix(s, inner, prefix, sizeof(prefix)));
  PetscCall(KSPCreate(s->comm, ksp));
  PetscCall(KSPSetOptionsPrefix(*ksp, prefix));
  PetscCall(KSPSetType(*ksp, KSPGMRES));
  PetscCall(KSPSetPCSide(*ksp, PC_RIGHT));
  PetscCall(KSPSetNormType(*ksp, KSP_NORM_UNPRECONDITIONED));
  PetscCall(KSPGetPC(*ksp, &pc));
  PetscCall(PCSetType(pc, PCSHELL));
  PetscCall(PCShellSetContext(pc, nt));
  PetscCall(PCShellSetApply(pc, ApplyStaleFactor));
  PetscCall(PCShellSetName(pc, name));
  PetscCall(KSPSetErrorIfNotConverged(*ksp, PETSC_FALSE));
  PetscFunctionReturn(0);
}

/* One rank: a direct LU, PETSc's own with an AMD ordering (the fastest measured on the Jacobians of confine500 and
   biaxial 20k), or Cholesky without friction (ChooseFactorization, at each step's set-up). Several ranks: chosen each step by
   ChooseLinearSolver. -solver_ksp_type, -solver_pc_type, -solver_pc_factor_mat_solver_type mumps (then with its null-pivot detection,
   EnableNullPivots) and the like choose otherwise. */
PetscErrorCode NewtonCreateLinearSolver(KergsSolver s, Newton *nt)
{
  PC          pc;
  PetscMPIInt size;
  char        prefix[256];

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(s->comm, &size));
  PetscCall(KergsSolverInnerPrefix(s, "solver_", prefix, sizeof(prefix)));
  PetscCall(KSPCreate(s->comm, &nt->ksp));
  PetscCall(KSPSetOptionsPrefix(nt->ksp, prefix));
  PetscCall(KSPSetType(nt->ksp, KSPPREONLY));
  PetscCall(KSPGetPC(nt->ksp, &pc));
  PetscCall(PCSetType(pc, PCLU));
  PetscCall(PCFactorSetMatSolverType(pc, size > 1 ? MATSOLVERMUMPS : MATSOLVERPETSC)); /* -solver_pc_type lu on several */
  PetscCall(PCFactorSetMatOrderingType(pc, MATORDERINGAMD)); /* 1.6-2.5 times faster than nd here; natural on one rank
                                                                 when J arrives presorted (PresortContacts) */
  PetscCall(KSPSetErrorIfNotConverged(nt->ksp, PETSC_FALSE));
  /* the reuse solver: GMRES on J preconditioned by ksp's last factorization of an earlier J */
  PetscCall(CreateFactorPreconditionedGMRES(s, nt, "solver_reuse_", "the last factorization of J", &nt->kreuse));
  /* -solver_prox kernel: GMRES on J_P preconditioned by ksp's factorization of J (sigma I) */
  PetscCall(CreateFactorPreconditionedGMRES(s, nt, "solver_prox_", "the factorization of J with sigma I", &nt->kprox));
  PetscCall(KSPSetTolerances(nt->kprox, 1e-8, PETSC_DEFAULT, PETSC_DEFAULT, 1000));
  PetscCall(KSPGMRESSetRestart(nt->kprox, 100));
  PetscFunctionReturn(0);
}
