/* A hand-built contact problem shared by the sweep tests (tests/test_sweep.c) and the sweep benchmark
   (scripts/bench_micro.c): a triangular lattice of disks with W = H^T M^-1 H + shift I, distributed in contiguous
   blocks of contacts. Reproducible on any number of ranks (every number comes from a hash of an index). */
#ifndef KERGS_TESTS_LATTICE_H
#define KERGS_TESTS_LATTICE_H

#include "internals.h"

/* A reproducible number in [0, 1) from an integer (splitmix64 finaliser). */
static PetscReal Hash01(unsigned long long x)
{
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  x = x ^ (x >> 31);
  return (PetscReal)(x >> 11) / 9007199254740992.0;
}

/* Local contacts of this rank when ntotal contacts are split in contiguous blocks (PETSc's default split). */
static PetscErrorCode LocalCount(MPI_Comm comm, PetscInt ntotal, PetscInt *nloc)
{
  PetscFunctionBeginUser;
  *nloc = PETSC_DECIDE;
  PetscCall(PetscSplitOwnership(comm, nloc, &ntotal));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------------
   Triangular lattice of gx x gy disks, contacts with the right, upper and upper-right neighbours (contact
   3 g + d, d = 0, 1, 2, kept when the neighbour exists; numbered in that order). Normals are the lattice
   directions perturbed by a reproducible angle. W = H^T M^-1 H + shift I over ncomp components per contact,
   rows distributed in contiguous blocks of contacts. */
typedef struct {
  PetscInt   gx, gy, ncontact;
  PetscInt  *ga, *gb; /* bodies a (neighbour) and b of each contact */
  PetscReal *nx, *ny;
} Lattice;

static PetscErrorCode LatticeCreate(PetscInt gx, PetscInt gy, Lattice *L)
{
  const PetscInt di[3] = {1, 0, 1}, dj[3] = {0, 1, 1};
  PetscInt       i, j, d, k = 0;

  PetscFunctionBeginUser;
  L->gx = gx;
  L->gy = gy;
  PetscCall(PetscMalloc4(3 * gx * gy, &L->ga, 3 * gx * gy, &L->gb, 3 * gx * gy, &L->nx, 3 * gx * gy, &L->ny));
  for (j = 0; j < gy; j++)
    for (i = 0; i < gx; i++)
      for (d = 0; d < 3; d++) {
        PetscReal ang;

        if (i + di[d] >= gx || j + dj[d] >= gy) continue;
        L->gb[k] = i + gx * j;
        L->ga[k] = i + di[d] + gx * (j + dj[d]);
        ang      = PetscAtan2Real((PetscReal)dj[d], (PetscReal)di[d]) + 0.2 * (Hash01(7 * k + 1) - 0.5);
        L->nx[k] = PetscCosReal(ang);
        L->ny[k] = PetscSinReal(ang);
        k++;
      }
  L->ncontact = k;
  PetscFunctionReturn(0);
}

static PetscErrorCode LatticeDestroy(Lattice *L)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree4(L->ga, L->gb, L->nx, L->ny));
  PetscFunctionReturn(0);
}

/* Sets the column(s) of contact k in Hs = M^{-1/2} H: force r_n n + r_t t and torque -R r_t on a, the
   opposite force and torque -R r_t on b (the statics of a contact). Disk radius R = 0.5, mass in [1, 2]. */
static PetscErrorCode LatticeSetContactColumns(const Lattice *L, PetscInt k, PetscInt ncomp, Mat Hs)
{
  const PetscReal R       = 0.5;
  const PetscInt  body[2] = {L->ga[k], L->gb[k]};
  const PetscReal sign[2] = {1.0, -1.0};
  PetscInt        s;

  PetscFunctionBeginUser;
  for (s = 0; s < 2; s++) {
    const PetscReal m = 1.0 + Hash01(3 * body[s] + 2), Inertia = 0.5 * m * R * R;
    const PetscInt  rows[3] = {3 * body[s], 3 * body[s] + 1, 3 * body[s] + 2};
    const PetscInt  cols[2] = {ncomp * k, ncomp * k + 1};
    PetscScalar     v[3][2];

    v[0][0] = sign[s] * L->nx[k] / PetscSqrtReal(m);
    v[1][0] = sign[s] * L->ny[k] / PetscSqrtReal(m);
    v[2][0] = 0.0;
    v[0][1] = -sign[s] * L->ny[k] / PetscSqrtReal(m); /* t = (-n_y, n_x) */
    v[1][1] = sign[s] * L->nx[k] / PetscSqrtReal(m);
    v[2][1] = -R / PetscSqrtReal(Inertia);
    if (ncomp == 2)
      PetscCall(MatSetValues(Hs, 3, rows, 2, cols, &v[0][0], INSERT_VALUES));
    else {
      PetscScalar vn[2] = {v[0][0], v[1][0]};

      PetscCall(MatSetValues(Hs, 2, rows, 1, cols, vn, INSERT_VALUES));
    }
  }
  PetscFunctionReturn(0);
}

/* W, v^d, mu and activity for the lattice on comm: contact k is inactive when k % 7 == 3; v^d_n in
   [-1, 0.5), v^d_t in [-1, 1). */
static PetscErrorCode LatticeProblem(MPI_Comm comm, const Lattice *L, PetscInt ncomp, PetscReal mu, PetscReal shift, Mat *W, Vec *vd,
                                     PetscReal **mus, PetscBool **active)
{
  const PetscInt ngrain = L->gx * L->gy;
  Mat            Hs;
  PetscInt       k, c, kstart, kend, nloc;

  PetscFunctionBeginUser;
  PetscCall(LocalCount(comm, L->ncontact, &nloc));
  /* columns by contact, so that W = Hs^T Hs has ncomp x ncomp blocks: stored as BAIJ for the sweep when ncomp > 1 */
  PetscCall(MatCreate(comm, &Hs));
  PetscCall(MatSetSizes(Hs, PETSC_DECIDE, ncomp * nloc, 3 * ngrain, ncomp * L->ncontact));
  PetscCall(MatSetBlockSizes(Hs, 1, ncomp));
  PetscCall(MatSetType(Hs, MATAIJ));
  PetscCall(MatSeqAIJSetPreallocation(Hs, 14 * ncomp, NULL));
  PetscCall(MatMPIAIJSetPreallocation(Hs, 14 * ncomp, NULL, 14 * ncomp, NULL));
  PetscCall(MatSetOption(Hs, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_FALSE));
  PetscCall(MatGetOwnershipRangeColumn(Hs, &kstart, &kend));
  kstart /= ncomp;
  kend /= ncomp;
  for (k = kstart; k < kend; k++) PetscCall(LatticeSetContactColumns(L, k, ncomp, Hs));
  PetscCall(MatAssemblyBegin(Hs, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(Hs, MAT_FINAL_ASSEMBLY));
  PetscCall(MatTransposeMatMult(Hs, Hs, MAT_INITIAL_MATRIX, PETSC_DEFAULT, W));
  if (ncomp > 1) PetscCall(MatConvert(*W, MATBAIJ, MAT_INPLACE_MATRIX, W));
  PetscCall(MatShift(*W, shift));
  PetscCall(MatDestroy(&Hs));

  PetscCall(MatCreateVecs(*W, vd, NULL));
  PetscCall(PetscMalloc2(kend - kstart, mus, kend - kstart, active));
  for (k = kstart; k < kend; k++) {
    (*mus)[k - kstart]    = mu;
    (*active)[k - kstart] = (PetscBool)(k % 7 != 3);
    for (c = 0; c < ncomp; c++)
      PetscCall(VecSetValue(*vd, ncomp * k + c, c == 0 ? -1.0 + 1.5 * Hash01(11 * k + 5) : -1.0 + 2.0 * Hash01(13 * k + 9), INSERT_VALUES));
  }
  PetscCall(VecAssemblyBegin(*vd));
  PetscCall(VecAssemblyEnd(*vd));
  PetscFunctionReturn(0);
}

#endif
