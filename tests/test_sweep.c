/* Tests of the NLGS sweep (src/solver/sweep.c) on problems built by hand:
   - a column of disks on the ground under gravity, frictionless (known static solution r_k = g dt sum_{j>=k} m_j),
     with an inactive ceiling contact that would close if it were active;
   - a triangular lattice of disks, W = H^T M^-1 H + s I (positive definite), frictionless and frictional, some
     contacts inactive: the distributed solution equals the one computed on one rank;
   - W stored by its upper block triangle (SBAIJ) sweeps as W stored whole, on any number of ranks;
   - the NLGS-Jac entry points (extra right-hand side, replacement diagonal blocks) against the equivalent
     problem (W + omega I) r + vd - omega r~.
   The lattice is built by tests/lattice.h; its timing (ns per contact per sweep) is a benchmark, scripts/bench_micro.c. */
#include "testing.h"
#include "lattice.h"

static const char help[] = "Tests of the NLGS sweep.\n";

/* Sweeps from r = 0 until quad < tol (at most maxit). Returns the number of sweeps and the quad of the first sweep;
   checks that quad fell below tol (label names the problem). */
static PetscErrorCode SolveBySweeps(const char *label, KergsSweep sweep, Vec r, Vec vd, const PetscReal *extra, const PetscReal *Wd,
                                    PetscReal tol, PetscInt maxit, PetscInt *its, PetscReal *quad0)
{
  KergsSweepMeasures m;
  PetscInt           k;

  PetscFunctionBeginUser;
  PetscCall(VecSet(r, 0.0));
  for (k = 0; k < maxit; k++) {
    PetscCall(KergsSweepRun(sweep, r, vd, extra, Wd, &m));
    if (k == 0) *quad0 = m.quad;
    if (m.quad < tol) break;
  }
  *its = PetscMin(k + 1, maxit);
  PetscCall(Checkf((PetscBool)(k < maxit), m.quad, tol, "%s: sweeps reach quad < %g within %" PetscInt_FMT " (quad at exit)", label,
                   (double)tol, maxit));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------------
   Column of N disks of masses m_k resting on the ground (contact 0: ground-disk 0; contact k: disk k-1 below,
   disk k above; normal upward, towards the upper body), plus contact N between disk N-1 and a ceiling driven
   downward at speed c (normal downward, towards the disk). Frictionless, one component per contact.
   W is tridiagonal: W_kk = 1/m_{k-1} + 1/m_k, W_k,k+1 = -1/m_k, W_00 = 1/m_0, W_NN = 1/m_{N-1}.
   v^d = (-g dt, 0, ..., 0, g dt - c). With the ceiling inactive the exact solution is static:
   r_k = g dt sum_{j >= k} m_j, r_N = 0. */
static PetscReal ColumnMass(PetscInt k) { return 1.0 + 0.1 * k; }

static PetscErrorCode BuildColumn(MPI_Comm comm, PetscInt N, PetscReal gdt, PetscReal c, Mat *W, Vec *vd, PetscBool **active)
{
  const PetscInt nc = N + 1;
  PetscInt       k, rstart, rend, nloc;

  PetscFunctionBeginUser;
  PetscCall(LocalCount(comm, nc, &nloc));
  PetscCall(MatCreateAIJ(comm, nloc, nloc, nc, nc, 3, NULL, 2, NULL, W));
  PetscCall(MatGetOwnershipRange(*W, &rstart, &rend));
  PetscCall(PetscMalloc1(rend - rstart, active));
  PetscCall(MatCreateVecs(*W, vd, NULL));
  for (k = rstart; k < rend; k++) {
    PetscReal diag = (k == 0 ? 0.0 : 1.0 / ColumnMass(k - 1)) + (k < N ? 1.0 / ColumnMass(k) : 0.0), vdk = 0.0;

    PetscCall(MatSetValue(*W, k, k, diag, INSERT_VALUES));
    if (k > 0) PetscCall(MatSetValue(*W, k, k - 1, -1.0 / ColumnMass(k - 1), INSERT_VALUES));
    if (k < N) PetscCall(MatSetValue(*W, k, k + 1, -1.0 / ColumnMass(k), INSERT_VALUES));
    if (k == 0) vdk = -gdt;
    if (k == N) vdk = gdt - c;
    PetscCall(VecSetValue(*vd, k, vdk, INSERT_VALUES));
    (*active)[k - rstart] = (PetscBool)(k < N);
  }
  PetscCall(MatAssemblyBegin(*W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*W, MAT_FINAL_ASSEMBLY));
  PetscCall(VecAssemblyBegin(*vd));
  PetscCall(VecAssemblyEnd(*vd));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestColumn(KergsSweep sweep)
{
  const PetscInt     N   = 12;
  const PetscReal    gdt = 9.81e-3;
  Mat                W;
  Vec                vd, r, v;
  PetscBool         *active;
  PetscInt           its, k, rstart, rend;
  PetscReal          quad0, res, err = 0.0, rmax = 0.0, above, rceiling = 0.0;
  const PetscScalar *ra;
  MPI_Comm           comm = PETSC_COMM_WORLD;

  PetscFunctionBeginUser;
  PetscCall(BuildColumn(comm, N, gdt, 3 * gdt, &W, &vd, &active));
  PetscCall(MatCreateVecs(W, &r, &v));
  PetscCall(KergsSweepSetUp(sweep, W, 1, NULL, active));
  /* r = 0 on a loaded column is as far from the solution as it can be, however small the load: the residual is 1 (an
     absolute |e| at r = 0 once let solvers stop there when a step's velocities were small) */
  PetscCall(KergsSweepNaturalResidual(sweep, r, vd, v, &res));
  PetscCall(Check((PetscBool)(PetscAbsReal(res - 1.0) < 1e-14), "column: natural residual 1 at r = 0", res, 1));
  PetscCall(VecScale(vd, 1e-9));
  PetscCall(KergsSweepNaturalResidual(sweep, r, vd, v, &res));
  PetscCall(
      Check((PetscBool)(PetscAbsReal(res - 1.0) < 1e-14), "column: natural residual 1 at r = 0 under a load 1e-9 times smaller", res, 1));
  PetscCall(VecScale(vd, 1e9));
  PetscCall(SolveBySweeps("column", sweep, r, vd, NULL, NULL, 1e-10, 20000, &its, &quad0));
  PetscCall(KergsSweepNaturalResidual(sweep, r, vd, v, &res));
  PetscCall(VecGetOwnershipRange(r, &rstart, &rend));
  PetscCall(VecGetArrayRead(r, &ra));
  for (k = rstart; k < rend; k++) {
    PetscInt j;

    for (above = 0.0, j = k; j < N; j++) above += gdt * ColumnMass(j);
    err  = PetscMax(err, PetscAbsReal(ra[k - rstart] - above));
    rmax = PetscMax(rmax, above);
    if (k == N) rceiling = PetscAbsReal(ra[k - rstart]);
  }
  PetscCall(VecRestoreArrayRead(r, &ra));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &err, 1, MPIU_REAL, MPIU_MAX, comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &rmax, 1, MPIU_REAL, MPIU_MAX, comm));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &rceiling, 1, MPIU_REAL, MPIU_MAX, comm));
  PetscCall(PetscPrintf(comm, "column of %" PetscInt_FMT " disks: %" PetscInt_FMT " sweeps\n", N, its));
  PetscCall(Check((PetscBool)(rceiling == 0.0), "column: the inactive ceiling contact carries r = 0", rceiling, 0));
  PetscCall(Check((PetscBool)(PetscAbsReal(quad0 - 1.0) < 1e-14), "column: the first sweep from r = 0 has quad = 1", quad0, 1));
  PetscCall(Check((PetscBool)(res < 1e-8), "column: natural residual", res, 1e-8));
  PetscCall(Check((PetscBool)(err < 1e-7 * rmax), "column: impulses = weights carried (|r - r_exact| / |r_exact|)", err / rmax, 1e-7));
  /* all contacts open: vd >= 0 gives r = 0 and a natural residual of exactly 0 (e = 0) */
  PetscCall(VecAbs(vd));
  PetscCall(SolveBySweeps("column pulled apart", sweep, r, vd, NULL, NULL, 1e-10, 10, &its, &quad0));
  PetscCall(VecNorm(r, NORM_INFINITY, &err));
  PetscCall(KergsSweepNaturalResidual(sweep, r, vd, v, &res));
  PetscCall(Check((PetscBool)(err == 0.0), "column pulled apart (v^d >= 0): r = 0", err, 0));
  PetscCall(
      Check((PetscBool)(res == 0.0 && quad0 == 0.0), "column pulled apart: quad 0 and natural residual 0 (their sum)", res + quad0, 0));
  PetscCall(KergsSweepReset(sweep)); /* active is freed below */
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&v));
  PetscCall(VecDestroy(&vd));
  PetscCall(MatDestroy(&W));
  PetscCall(PetscFree(active));
  PetscFunctionReturn(0);
}

/* Solve the lattice problem on comm (to quad < 1e-12); check residual and inactive contacts. Returns r. */
static PetscErrorCode SolveLattice(MPI_Comm comm, KergsSweep sweep, const Lattice *L, PetscInt ncomp, PetscReal mu, Vec *r, PetscReal *res,
                                   PetscInt *its)
{
  Mat                W;
  Vec                vd, v;
  PetscReal         *mus, quad0, rin = 0.0;
  PetscBool         *active;
  PetscInt           k, c, n;
  const PetscScalar *ra;

  PetscFunctionBeginUser;
  PetscCall(LatticeProblem(comm, L, ncomp, mu, 1.0, &W, &vd, &mus, &active));
  PetscCall(MatCreateVecs(W, r, &v));
  PetscCall(KergsSweepSetUp(sweep, W, ncomp, mus, active));
  PetscCall(SolveBySweeps(comm == PETSC_COMM_SELF ? "lattice on 1 rank" : "lattice", sweep, *r, vd, NULL, NULL, 1e-12, 5000, its, &quad0));
  PetscCall(KergsSweepNaturalResidual(sweep, *r, vd, v, res));
  n = sweep->n;
  PetscCall(VecGetArrayRead(*r, &ra));
  for (k = 0; k < n; k++)
    if (!active[k])
      for (c = 0; c < ncomp; c++) rin = PetscMax(rin, PetscAbsReal(ra[k * ncomp + c]));
  PetscCall(VecRestoreArrayRead(*r, &ra));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &rin, 1, MPIU_REAL, MPIU_MAX, comm));
  PetscCall(Check((PetscBool)(rin == 0.0), "lattice: the inactive contacts carry r = 0 (largest |r|)", rin, 0));
  PetscCall(KergsSweepReset(sweep)); /* mus and active are freed below */
  PetscCall(PetscFree2(mus, active));
  PetscCall(VecDestroy(&vd));
  PetscCall(VecDestroy(&v));
  PetscCall(MatDestroy(&W));
  PetscFunctionReturn(0);
}

/* The lattice solved on all ranks equals the lattice solved on one rank (each rank solves the whole
   problem on PETSC_COMM_SELF for reference). W is positive definite: r is unique when frictionless. */
static PetscErrorCode TestLatticeRanks(KergsSweep sweep, PetscInt ncomp, PetscReal mu)
{
  MPI_Comm    comm = PETSC_COMM_WORLD;
  KergsSweep  seq;
  Lattice     L;
  Vec         r, rseq, rall;
  VecScatter  toall;
  PetscReal   res, resseq, diff, nrm;
  PetscInt    its, itsseq;
  PetscMPIInt size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(LatticeCreate(9, 8, &L));
  PetscCall(SolveLattice(comm, sweep, &L, ncomp, mu, &r, &res, &its));
  PetscCall(KergsSweepCreate(PETSC_COMM_SELF, &seq));
  PetscCall(SolveLattice(PETSC_COMM_SELF, seq, &L, ncomp, mu, &rseq, &resseq, &itsseq));
  PetscCall(KergsSweepDestroy(&seq));
  PetscCall(VecScatterCreateToAll(r, &toall, &rall));
  PetscCall(VecScatterBegin(toall, r, rall, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecScatterEnd(toall, r, rall, INSERT_VALUES, SCATTER_FORWARD));
  PetscCall(VecNorm(rseq, NORM_INFINITY, &nrm));
  PetscCall(VecAXPY(rall, -1.0, rseq));
  PetscCall(VecNorm(rall, NORM_INFINITY, &diff));
  PetscCall(PetscPrintf(comm,
                        "lattice %" PetscInt_FMT " contacts, ncomp %" PetscInt_FMT ", mu %g: %d rank(s) %" PetscInt_FMT
                        " sweeps; 1 rank %" PetscInt_FMT " sweeps\n",
                        L.ncontact, ncomp, (double)mu, size, its, itsseq));
  PetscCall(Checkf((PetscBool)(res < 1e-8 && resseq < 1e-8), PetscMax(res, resseq), 1e-8,
                   "lattice ncomp %" PetscInt_FMT " mu %g: natural residual on %d and 1 rank(s)", ncomp, (double)mu, size));
  PetscCall(Checkf((PetscBool)(nrm > 0 && diff < 1e-8 * nrm), nrm > 0 ? diff / nrm : -1, 1e-8,
                   "lattice ncomp %" PetscInt_FMT " mu %g: %d-rank solution = 1-rank one (relative)", ncomp, (double)mu, size));
  PetscCall(VecScatterDestroy(&toall));
  PetscCall(VecDestroy(&rall));
  PetscCall(VecDestroy(&rseq));
  PetscCall(VecDestroy(&r));
  PetscCall(LatticeDestroy(&L));
  PetscFunctionReturn(0);
}

/* r after nsweep sweeps from r = 0 (and the last quad) on the lattice problem W stored as given. */
static PetscErrorCode SweepsFromZero(Mat W, Vec vd, PetscInt ncomp, const PetscReal *mus, const PetscBool *active, PetscInt nsweep, Vec r,
                                     PetscReal *quad)
{
  KergsSweep         sw;
  KergsSweepMeasures m = {0, 0};

  PetscFunctionBeginUser;
  PetscCall(KergsSweepCreate(PetscObjectComm((PetscObject)W), &sw));
  PetscCall(KergsSweepSetUp(sw, W, ncomp, mus, active));
  PetscCall(VecSet(r, 0.0));
  for (PetscInt k = 0; k < nsweep; k++) PetscCall(KergsSweepRun(sw, r, vd, NULL, NULL, &m));
  *quad = m.quad;
  PetscCall(KergsSweepDestroy(&sw));
  PetscFunctionReturn(0);
}

/* W stored by its upper block triangle (SBAIJ, block size ncomp) gives the same sweeps as W stored whole, up to
   rounding: same Gauss-Seidel order inside a rank, same Jacobi coupling across ranks (the lower ranks' part
   arriving through the reverse scatter). */
static PetscErrorCode TestUpperStorage(PetscInt ncomp, PetscReal mu)
{
  MPI_Comm   comm = PETSC_COMM_WORLD;
  Lattice    L;
  Mat        W, Wu;
  Vec        vd, r, ru;
  PetscReal *mus, q, qu, diff, nrm;
  PetscBool *active;

  PetscFunctionBeginUser;
  PetscCall(LatticeCreate(9, 8, &L));
  PetscCall(LatticeProblem(comm, &L, ncomp, mu, 0.05, &W, &vd, &mus, &active));
  PetscCall(MatSetOption(W, MAT_SYMMETRIC, PETSC_TRUE));
  PetscCall(MatConvert(W, MATSBAIJ, MAT_INITIAL_MATRIX, &Wu));
  PetscCall(MatCreateVecs(W, &r, NULL));
  PetscCall(VecDuplicate(r, &ru));
  PetscCall(SweepsFromZero(W, vd, ncomp, mus, active, 7, r, &q));
  PetscCall(SweepsFromZero(Wu, vd, ncomp, mus, active, 7, ru, &qu));
  PetscCall(VecNorm(r, NORM_INFINITY, &nrm));
  PetscCall(VecAXPY(ru, -1.0, r));
  PetscCall(VecNorm(ru, NORM_INFINITY, &diff));
  PetscCall(Checkf((PetscBool)(nrm > 0 && diff <= 1e-12 * nrm), nrm > 0 ? diff / nrm : -1, 1e-12,
                   "upper storage, ncomp %" PetscInt_FMT " mu %g: 7 sweeps give r of whole storage (relative)", ncomp, (double)mu));
  PetscCall(Checkf((PetscBool)(PetscAbsReal(qu - q) <= 1e-10 * q), qu, q,
                   "upper storage, ncomp %" PetscInt_FMT " mu %g: same quad after 7 sweeps", ncomp, (double)mu));
  PetscCall(PetscFree2(mus, active));
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&ru));
  PetscCall(VecDestroy(&vd));
  PetscCall(MatDestroy(&W));
  PetscCall(MatDestroy(&Wu));
  PetscCall(LatticeDestroy(&L));
  PetscFunctionReturn(0);
}

/* NLGS-Jac entry points with Z = omega I (Algorithm 6): Z_aa = omega I, z~ = omega r~, z^{k-1} = omega r^{k-1},
   so extra_a = -z~_a + z^{k-1}_a - Z_aa r^{k-1}_a = -omega r~_a and the blocks are W_aa + omega I. The limit
   must solve (W + omega I) r + v^d - omega r~ with the law, checked by a second sweep set up on W + omega I. */
static PetscErrorCode TestRegularisedEntryPoints(KergsSweep sweep)
{
  MPI_Comm           comm  = PETSC_COMM_WORLD;
  const PetscInt     ncomp = 2;
  const PetscReal    omega = 0.7;
  KergsSweep         check;
  Lattice            L;
  Mat                W, Wreg;
  Vec                vd, vdreg, r, rtilde, v;
  PetscReal         *mus, *extra, *Wd, res, quad0, resplain;
  PetscBool         *active;
  PetscInt           its, i, n;
  const PetscScalar *rt;

  PetscFunctionBeginUser;
  PetscCall(LatticeCreate(7, 6, &L));
  PetscCall(LatticeProblem(comm, &L, ncomp, 0.4, 0.2, &W, &vd, &mus, &active));
  PetscCall(MatCreateVecs(W, &r, &v));
  PetscCall(VecDuplicate(vd, &rtilde));
  PetscCall(VecSetRandom(rtilde, NULL));
  PetscCall(KergsSweepSetUp(sweep, W, ncomp, mus, active));
  n = sweep->n;
  PetscCall(PetscMalloc2(n * ncomp, &extra, n * ncomp * ncomp, &Wd));
  PetscCall(VecGetArrayRead(rtilde, &rt));
  for (i = 0; i < n * ncomp; i++) extra[i] = -omega * rt[i];
  PetscCall(VecRestoreArrayRead(rtilde, &rt));
  PetscCall(KergsSweepGetDiagonalBlocks(sweep, Wd));
  for (i = 0; i < n * ncomp * ncomp; i++) Wd[i] += (i % (ncomp * ncomp)) % (ncomp + 1) == 0 ? omega : 0.0;
  PetscCall(SolveBySweeps("regularised sweep", sweep, r, vd, extra, Wd, 1e-12, 5000, &its, &quad0));
  PetscCall(KergsSweepNaturalResidual(sweep, r, vd, v, &resplain));

  PetscCall(MatDuplicate(W, MAT_COPY_VALUES, &Wreg));
  PetscCall(MatShift(Wreg, omega));
  PetscCall(VecDuplicate(vd, &vdreg));
  PetscCall(VecWAXPY(vdreg, -omega, rtilde, vd));
  PetscCall(KergsSweepCreate(comm, &check));
  PetscCall(KergsSweepSetUp(check, Wreg, ncomp, mus, active));
  PetscCall(KergsSweepNaturalResidual(check, r, vdreg, v, &res));
  PetscCall(PetscPrintf(comm, "regularised sweep (extra, W_aa + omega I): %" PetscInt_FMT " sweeps\n", its));
  PetscCall(Check((PetscBool)(res < 1e-8), "regularised sweep: natural residual of (W + omega I) r + v^d - omega r~", res, 1e-8));
  PetscCall(Check((PetscBool)(resplain > 1e-4), "regularised sweep: extra/Wdiag used (residual of the plain problem stays large)", resplain,
                  1e-4));
  PetscCall(KergsSweepDestroy(&check));
  PetscCall(KergsSweepReset(sweep));
  PetscCall(PetscFree2(extra, Wd));
  PetscCall(PetscFree2(mus, active));
  PetscCall(VecDestroy(&r));
  PetscCall(VecDestroy(&v));
  PetscCall(VecDestroy(&vd));
  PetscCall(VecDestroy(&vdreg));
  PetscCall(VecDestroy(&rtilde));
  PetscCall(MatDestroy(&W));
  PetscCall(MatDestroy(&Wreg));
  PetscCall(LatticeDestroy(&L));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  KergsSweep sweep;

  PetscFunctionBeginUser;
  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCall(KergsSweepCreate(PETSC_COMM_WORLD, &sweep));
  /* one sweep object for every problem: SetUp on a new W resets the previous one */
  PetscCall(TestColumn(sweep));
  PetscCall(TestLatticeRanks(sweep, 1, 0.0));
  PetscCall(TestLatticeRanks(sweep, 2, 0.0));
  PetscCall(TestLatticeRanks(sweep, 2, 0.3));
  PetscCall(TestUpperStorage(1, 0.0));
  PetscCall(TestUpperStorage(2, 0.3));
  PetscCall(TestRegularisedEntryPoints(sweep));
  PetscCall(KergsSweepDestroy(&sweep));
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
