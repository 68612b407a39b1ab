/* kergs operators: the Delassus operator W = H_f^T M^-1 H_f of one step, assembled body by body (the rest of the
   operators, H_f^T, H_g^T, v^d and the velocity update, is in src/operators/operators.c). */
#include <kergs/private/operatorsimpl.h>

/*
   M is block diagonal by bodies, so W = sum over free bodies q of H_q^T M_q^-1 H_q: body q couples every pair of
   contacts (alpha, beta) that touch it, by the block H_alpha,q M_q^-1 H_beta,q^T (ncomp x ncomp; H_alpha,q are the
   rows of contact alpha on q's DOFs). Each rank adds the terms of the disks it owns: their contacts are its own
   plus its foreign ones (detect.h), all known here with their global indices; rows of foreign contacts go to their
   owners through PETSc's stash. A free wall's terms are added by each rank for its own contacts at that wall, from
   the list of every contact at the wall (gathered: a free wall couples all of them). The pattern is counted
   exactly beforehand: row alpha holds the contacts at its body a (always owned by alpha's owner) and at its body
   b, alpha itself in both; for a ghost b the counts come from b's owner. W is symmetric: only its upper block
   triangle is stored (SBAIJ, blocks W_alpha,beta with beta >= alpha, diagonal blocks whole), by ncomp x ncomp
   blocks, one block row per contact (block size 1 when frictionless), as the sweep reads it. Only those blocks are
   computed and counted. Nothing of the size of W or H_f is built on the side, except, on several ranks and for the
   solver types that read whole rows, W with both triangles (KergsOperatorsSetBothTriangles), assembled the same way.
*/

/* A contact at one body: global index, owning rank, whether it is coupled to the others (active, or W over all
   pairs), and its rows of H_f^T on the body's DOFs (h[c * nd + j]). */
typedef struct {
  PetscInt    index;
  PetscMPIInt owner;
  PetscBool   coupled;
  PetscReal   h[KERGS_MAXCOMP * (KERGS_DIM + KERGS_NROT)];
} BodyContact;

/* Whether W stores the block W_alpha,beta: the own block always; another only between coupled contacts. */
static inline PetscBool StoredBlock(const BodyContact *alpha, const BodyContact *beta)
{
  return (PetscBool)(alpha->index == beta->index || (alpha->coupled && beta->coupled));
}

/* The rows of contact ct restricted to the DOFs [dof, dof + nd) of one of its bodies. */
static void RestrictToBody(KergsOperators ops, const StepData *sd, const KergsContact *ct, PetscInt dof, PetscInt nd, PetscReal *h)
{
  HtRow fr, gr;

  for (PetscInt i = 0; i < ops->ncomp * nd; i++) h[i] = 0.0;
  for (PetscInt c = 0; c < ops->ncomp; c++) {
    KergsOperatorsContactRows(ops, sd, ct, c, &fr, &gr);
    for (PetscInt j = 0; j < fr.ncol; j++)
      if (fr.col[j] >= dof && fr.col[j] < dof + nd) h[c * nd + fr.col[j] - dof] = fr.val[j];
  }
}

/* The contacts at each owned disk, in CSR form (start[q] .. start[q+1] in list): entry k < n is owned contact k,
   entry n + f is foreign contact f. */
static PetscErrorCode DiskIncidence(const StepData *sd, PetscInt **start, PetscInt **list)
{
  const PetscInt nq = sd->D.nowned;
  PetscInt      *fill;

  PetscFunctionBeginUser;
  PetscCall(PetscCalloc1(nq + 1, start));
  for (PetscInt k = 0; k < sd->ncontacts; k++) {
    (*start)[sd->c[k].a + 1]++;
    if (sd->c[k].kind == KERGS_CONTACT_DISK_DISK && sd->c[k].b < nq) (*start)[sd->c[k].b + 1]++;
  }
  for (PetscInt f = 0; f < sd->nforeign; f++) (*start)[sd->foreign[f].b + 1]++;
  for (PetscInt q = 0; q < nq; q++) (*start)[q + 1] += (*start)[q];
  PetscCall(PetscMalloc1((*start)[nq] + 1, list));
  PetscCall(PetscMalloc1(nq + 1, &fill));
  PetscCall(PetscArraycpy(fill, *start, nq));
  for (PetscInt k = 0; k < sd->ncontacts; k++) {
    (*list)[fill[sd->c[k].a]++] = k;
    if (sd->c[k].kind == KERGS_CONTACT_DISK_DISK && sd->c[k].b < nq) (*list)[fill[sd->c[k].b]++] = k;
  }
  for (PetscInt f = 0; f < sd->nforeign; f++) (*list)[fill[sd->foreign[f].b]++] = sd->ncontacts + f;
  PetscCall(PetscFree(fill));
  PetscFunctionReturn(0);
}

/* The contacts at owned disk q, into bc[0 .. m): index and owner, and with rows their rows on q's DOFs (the pattern
   counts need no rows). */
static PetscInt DiskContacts(KergsOperators ops, const StepData *sd, const PetscInt *start, const PetscInt *list, PetscInt q,
                             PetscBool rows, BodyContact *bc)
{
  const PetscInt nd = ops->ndof_disk, dof = KergsOperatorsDiskDof(ops, sd->D.gidx[q]);
  PetscMPIInt    rank;
  PetscInt       m = 0;

  (void)MPI_Comm_rank(ops->comm, &rank);
  for (PetscInt j = start[q]; j < start[q + 1]; j++, m++) {
    const PetscInt      e = list[j];
    const KergsContact *c = e < sd->ncontacts ? &sd->c[e] : &sd->foreign[e - sd->ncontacts];
    bc[m].index           = e < sd->ncontacts ? sd->start + e : sd->foreign_index[e - sd->ncontacts];
    bc[m].owner           = e < sd->ncontacts ? rank : (PetscMPIInt)sd->D.ghost_owner[c->a - sd->D.nowned];
    bc[m].coupled         = ops->W_active_only ? KergsContactIsActive(&sd->activity, c) : PETSC_TRUE;
    if (rows) RestrictToBody(ops, sd, c, dof, nd, bc[m].h);
  }
  return m;
}

/* Every contact at free wall w, on every rank (rows on the wall's KERGS_DIM DOFs); *m of them in *bc (PetscFree). */
static PetscErrorCode WallContacts(KergsOperators ops, const StepData *sd, PetscInt w, PetscInt *m, BodyContact **bc)
{
  PetscMPIInt  size, rank, nmine = 0, *counts, *displs;
  BodyContact *mine;
  PetscInt     total = 0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(ops->comm, &size));
  PetscCallMPI(MPI_Comm_rank(ops->comm, &rank));
  for (PetscInt k = 0; k < sd->ncontacts; k++) nmine += sd->c[k].kind == KERGS_CONTACT_DISK_WALL && sd->c[k].b == w;
  PetscCall(PetscMalloc1(nmine + 1, &mine));
  for (PetscInt k = 0, i = 0; k < sd->ncontacts; k++)
    if (sd->c[k].kind == KERGS_CONTACT_DISK_WALL && sd->c[k].b == w) {
      mine[i].index   = sd->start + k;
      mine[i].owner   = rank;
      mine[i].coupled = ops->W_active_only ? KergsContactIsActive(&sd->activity, &sd->c[k]) : PETSC_TRUE;
      RestrictToBody(ops, sd, &sd->c[k], ops->wall_dof[w], KERGS_DIM, mine[i++].h);
    }
  PetscCall(PetscMalloc2(size, &counts, size, &displs));
  nmine *= (PetscMPIInt)sizeof(BodyContact);
  PetscCallMPI(MPI_Allgather(&nmine, 1, MPI_INT, counts, 1, MPI_INT, ops->comm));
  for (PetscMPIInt p = 0; p < size; p++) {
    displs[p] = (PetscMPIInt)(total * (PetscInt)sizeof(BodyContact));
    total += counts[p] / (PetscMPIInt)sizeof(BodyContact);
  }
  PetscCall(PetscMalloc1(total + 1, bc));
  PetscCallMPI(MPI_Allgatherv(mine, nmine, MPI_BYTE, *bc, counts, displs, MPI_BYTE, ops->comm));
  *m = total;
  PetscCall(PetscFree2(counts, displs));
  PetscCall(PetscFree(mine));
  PetscFunctionReturn(0);
}

/* Block pattern counts of row alpha (global contact index `row`) from the contacts bc[0 .. m) at one of its bodies: the
   blocks W_alpha,beta with beta >= alpha (and StoredBlock), or every beta for W stored with both triangles (`both`).
   Alpha is among them; when it is counted twice (dup) it is taken off once. The diagonal part holds those of rank
   `owner`. */
static void CountBlocks(const BodyContact *bc, PetscInt m, PetscInt row, PetscMPIInt owner, PetscBool dup, PetscBool both, PetscInt *d,
                        PetscInt *o)
{
  const BodyContact *alpha = NULL;

  for (PetscInt j = 0; j < m && !alpha; j++)
    if (bc[j].index == row) alpha = &bc[j];
  for (PetscInt j = 0; j < m; j++) {
    if ((!both && bc[j].index < row) || !StoredBlock(alpha, &bc[j])) continue;
    if (bc[j].owner == owner)
      (*d)++;
    else
      (*o)++;
  }
  if (dup) (*d)--;
}

/* The counts of the rows of foreign contacts at owned disks, sent to their owners, added to dnz/onz there. */
static PetscErrorCode CountRemoteRows(KergsOperators ops, const StepData *sd, const PetscInt *start, const PetscInt *list, BodyContact *bc,
                                      PetscBool both, PetscInt *dnz, PetscInt *onz)
{
  PetscMPIInt size, *scount, *fill;
  PetscInt   *send, *recv, nrecv;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(ops->comm, &size));
  if (size == 1) PetscFunctionReturn(0);
  PetscCall(PetscCalloc2(size, &scount, size, &fill));
  PetscCall(PetscMalloc1(3 * sd->nforeign + 1, &send));
  for (PetscInt f = 0; f < sd->nforeign; f++) scount[sd->D.ghost_owner[sd->foreign[f].a - sd->D.nowned]]++;
  for (PetscMPIInt p = 1; p < size; p++) fill[p] = fill[p - 1] + scount[p - 1];
  for (PetscInt q = 0; q < sd->D.nowned; q++) {
    PetscInt m = -1;
    for (PetscInt j = start[q]; j < start[q + 1]; j++) {
      PetscInt    f = list[j] - sd->ncontacts, d = 0, o = 0, *r;
      PetscMPIInt p;
      if (f < 0) continue;
      if (m < 0) m = DiskContacts(ops, sd, start, list, q, PETSC_FALSE, bc);
      p = (PetscMPIInt)sd->D.ghost_owner[sd->foreign[f].a - sd->D.nowned];
      CountBlocks(bc, m, sd->foreign_index[f], p, PETSC_TRUE, both, &d, &o);
      r    = &send[3 * fill[p]++]; /* one record per foreign row: its index, then its counts */
      r[0] = sd->foreign_index[f];
      r[1] = d;
      r[2] = o;
    }
  }
  PetscCall(KergsExchangeRecords(ops->comm, 3 * sizeof(PetscInt), scount, send, NULL, &recv, &nrecv));
  nrecv *= 3;
  for (PetscInt i = 0; i < nrecv; i += 3) {
    const PetscInt k = recv[i] - sd->start;
    PetscCheck(k >= 0 && k < sd->ncontacts, PETSC_COMM_SELF, PETSC_ERR_PLIB, "W pattern: contact %" PetscInt_FMT " is not owned here",
               recv[i]);
    dnz[k] += recv[i + 1];
    onz[k] += recv[i + 2];
  }
  PetscCall(PetscFree(recv));
  PetscCall(PetscFree(send));
  PetscCall(PetscFree2(scount, fill));
  PetscFunctionReturn(0);
}

/* Add the blocks H_alpha,q M_q^-1 H_beta,q^T of body q (contacts bc[0 .. m), inverse masses minv on its nd DOFs)
   to the block rows of the contacts bc[rows[i]] (all of them when rows is NULL); only the upper blocks, beta >= alpha
   (global contact indices), as W is stored by its upper block triangle (W_beta,alpha = W_alpha,beta^T), or every
   block (`both`), a lower one computed as the transpose of its upper one, operation for operation, so that the two
   triangles are exact transposes (the diagonal blocks too: their entries below the diagonal are those above it). On
   one rank this is PETSc's conversion of the upper triangle to the bit; on several, the parallel upper triangle's
   diagonal blocks that receive another rank's term differ from it in rounding (measured: 1e-18 relative, in their
   off-diagonal entries only; tests/test_physics.c). */
static PetscErrorCode AddBodyBlocks(Mat W, PetscInt nc, PetscInt nd, const PetscReal *minv, const BodyContact *bc, PetscInt m,
                                    const PetscInt *rows, PetscInt nrows, PetscBool both, PetscInt *cols, PetscScalar *vals)
{
  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < (rows ? nrows : m); i++) {
    const BodyContact *a = &bc[rows ? rows[i] : i];
    PetscInt           n = 0;
    for (PetscInt j = 0; j < m; j++)
      if ((both || bc[j].index >= a->index) && StoredBlock(a, &bc[j])) cols[n++] = j;
    for (PetscInt k = 0; k < n; k++)
      for (PetscInt c = 0; c < nc; c++)
        for (PetscInt e = 0; e < nc; e++) {
          const BodyContact *b = &bc[cols[k]];
          PetscReal          w = 0.0;
          if (b->index > a->index || (b->index == a->index && (!both || c <= e)))
            for (PetscInt d = 0; d < nd; d++) w += a->h[c * nd + d] * minv[d] * b->h[e * nd + d];
          else /* (W_beta,alpha)_ec, as computed in beta's row (or the diagonal block's upper entry) */
            for (PetscInt d = 0; d < nd; d++) w += b->h[e * nd + d] * minv[d] * a->h[c * nd + d];
          vals[c * n * nc + k * nc + e] = w; /* row-major block row, as MatSetValuesBlocked takes it */
        }
    for (PetscInt k = 0; k < n; k++) cols[k] = bc[cols[k]].index;
    PetscCall(MatSetValuesBlocked(W, 1, &a->index, n, cols, vals, ADD_VALUES));
  }
  PetscFunctionReturn(0);
}

/* The free walls' terms: each rank adds the rows of its own contacts at each free wall to W; with the counts of those
   rows when dnz is given (then nothing is added). */
static PetscErrorCode AddWallTerms(KergsOperators ops, const StepData *sd, Mat W, PetscBool both, PetscInt *dnz, PetscInt *onz)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(ops->comm, &rank));
  for (PetscInt w = 0; w < sd->nwalls; w++) {
    BodyContact *bc;
    PetscInt     m, *rows, nrows = 0, *cols;
    PetscScalar *vals;
    PetscReal    minv[KERGS_DIM];

    if (sd->walls[w].kind != KERGS_WALL_FREE) continue;
    PetscCall(WallContacts(ops, sd, w, &m, &bc));
    PetscCall(PetscMalloc3(m + 1, &rows, m + 1, &cols, m * ops->ncomp * ops->ncomp + 1, &vals));
    for (PetscInt j = 0; j < m; j++)
      if (bc[j].owner == rank) rows[nrows++] = j;
    for (PetscInt d = 0; d < KERGS_DIM; d++) minv[d] = 1.0 / sd->walls[w].mass;
    if (dnz)
      for (PetscInt i = 0; i < nrows; i++)
        CountBlocks(bc, m, bc[rows[i]].index, rank, PETSC_TRUE, both, &dnz[bc[rows[i]].index - sd->start],
                    &onz[bc[rows[i]].index - sd->start]);
    else
      PetscCall(AddBodyBlocks(W, ops->ncomp, KERGS_DIM, minv, bc, m, rows, nrows, both, cols, vals));
    PetscCall(PetscFree3(rows, cols, vals));
    PetscCall(PetscFree(bc));
  }
  PetscFunctionReturn(0);
}

/* Exact block counts of this rank's rows: the contacts at body a (owned here), plus those at body b (owned here,
   from b's owner for a ghost, or at a free wall), alpha itself once. */
static PetscErrorCode CountPattern(KergsOperators ops, const StepData *sd, const PetscInt *start, const PetscInt *list, BodyContact *bc,
                                   PetscBool both, PetscInt *dnz, PetscInt *onz)
{
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_rank(ops->comm, &rank));
  for (PetscInt k = 0; k < sd->ncontacts; k++) dnz[k] = onz[k] = 0;
  for (PetscInt q = 0; q < sd->D.nowned; q++) {
    PetscInt m = -1;
    for (PetscInt j = start[q]; j < start[q + 1]; j++) {
      const PetscInt k = list[j];
      if (k >= sd->ncontacts) continue; /* a foreign row: counted by its owner, from CountRemoteRows */
      if (m < 0) m = DiskContacts(ops, sd, start, list, q, PETSC_FALSE, bc);
      CountBlocks(bc, m, sd->start + k, rank, (PetscBool)(q != sd->c[k].a), both, &dnz[k], &onz[k]); /* at b: alpha is counted already */
    }
  }
  PetscCall(CountRemoteRows(ops, sd, start, list, bc, both, dnz, onz));
  PetscCall(AddWallTerms(ops, sd, NULL, both, dnz, onz));
  PetscFunctionReturn(0);
}

/* W by its upper block triangle (SBAIJ), or with both triangles (BAIJ, or AIJ when frictionless: `both`). */
static PetscErrorCode ComputeDelassus(KergsOperators ops, const StepData *sd, PetscBool both, Mat *W)
{
  const PetscInt     nc = ops->ncomp, nd = ops->ndof_disk;
  PetscInt          *start, *list, *dnz, *onz, *cols, maxm = 1;
  BodyContact       *bc;
  PetscScalar       *vals;
  const PetscScalar *minv;

  PetscFunctionBeginUser;
  PetscCall(DiskIncidence(sd, &start, &list));
  for (PetscInt q = 0; q < sd->D.nowned; q++) maxm = PetscMax(maxm, start[q + 1] - start[q]);
  PetscCall(PetscMalloc5(maxm, &bc, maxm, &cols, maxm * nc * nc, &vals, sd->ncontacts + 1, &dnz, sd->ncontacts + 1, &onz));
  PetscCall(CountPattern(ops, sd, start, list, bc, both, dnz, onz));
  PetscCall(MatCreate(ops->comm, W));
  PetscCall(MatSetSizes(*W, sd->ncontacts * nc, sd->ncontacts * nc, PETSC_DETERMINE, PETSC_DETERMINE));
  PetscCall(MatSetBlockSize(*W, nc));
  if (!both) {
    PetscCall(MatSetType(*W, MATSBAIJ));
    PetscCall(MatSeqSBAIJSetPreallocation(*W, nc, 0, dnz));
    PetscCall(MatMPISBAIJSetPreallocation(*W, nc, 0, dnz, 0, onz));
  } else if (nc > 1) {
    PetscCall(MatSetType(*W, MATBAIJ));
    PetscCall(MatSeqBAIJSetPreallocation(*W, nc, 0, dnz));
    PetscCall(MatMPIBAIJSetPreallocation(*W, nc, 0, dnz, 0, onz));
  } else {
    PetscCall(MatSetType(*W, MATAIJ));
    PetscCall(MatSeqAIJSetPreallocation(*W, 0, dnz));
    PetscCall(MatMPIAIJSetPreallocation(*W, 0, dnz, 0, onz));
  }
  PetscCall(MatSetOption(*W, MAT_NEW_NONZERO_ALLOCATION_ERR, PETSC_TRUE));
  PetscCall(VecGetArrayRead(ops->Minv, &minv));
  for (PetscInt q = 0; q < sd->D.nowned; q++) {
    const PetscInt m = DiskContacts(ops, sd, start, list, q, PETSC_TRUE, bc);
    PetscCall(AddBodyBlocks(*W, nc, nd, &minv[q * nd], bc, m, NULL, m, both, cols, vals));
  }
  PetscCall(VecRestoreArrayRead(ops->Minv, &minv));
  PetscCall(AddWallTerms(ops, sd, *W, both, NULL, NULL));
  PetscCall(MatAssemblyBegin(*W, MAT_FINAL_ASSEMBLY));
  PetscCall(MatAssemblyEnd(*W, MAT_FINAL_ASSEMBLY));
  PetscCall(PetscFree5(bc, cols, vals, dnz, onz));
  PetscCall(PetscFree(start));
  PetscCall(PetscFree(list));
  PetscFunctionReturn(0);
}

/* Scalar nonzeros of the whole W, as if stored in full: nz_used counts ncomp^2 per stored block, and an SBAIJ W
   stores the upper block triangle only, so that full = 2 stored - (diagonal blocks: ncomp^2 per contact). */
static PetscErrorCode FullNonzerosW(Mat W, PetscReal *nnz)
{
  MatInfo  info;
  PetscInt N, bs;

  PetscFunctionBeginUser;
  PetscCall(MatGetInfo(W, MAT_GLOBAL_SUM, &info));
  PetscCall(MatGetSize(W, &N, NULL));
  PetscCall(MatGetBlockSize(W, &bs));
  *nnz = 2.0 * info.nz_used - (PetscReal)N * bs;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsAssembleW(KergsOperators ops, KergsScene scene, KergsContacts contacts, PetscBool activeonly)
{
  StepData sd;

  PetscFunctionBeginUser;
  PetscCheck(ops->Minv && ops->vd, ops->comm, PETSC_ERR_ORDER, "KergsOperatorsAssembleW: call KergsOperatorsAssembleH first");
  PetscCall(PetscLogEventBegin(KERGS_Assemble, 0, 0, 0, 0));
  PetscCall(KergsOperatorsReleaseW(ops));
  ops->W_active_only = activeonly;
  PetscCall(KergsOperatorsGetStepData(ops, scene, contacts, &sd));
  PetscCall(ComputeDelassus(ops, &sd, PETSC_FALSE, &ops->W));
  if (ops->both_triangles) PetscCall(ComputeDelassus(ops, &sd, PETSC_TRUE, &ops->Wboth));
  PetscCall(FullNonzerosW(ops->W, &ops->nnz_W));
  PetscCall(PetscLogEventEnd(KERGS_Assemble, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsOperatorsReleaseW(KergsOperators ops)
{
  PetscFunctionBeginUser;
  PetscCall(MatDestroy(&ops->W));
  PetscCall(MatDestroy(&ops->Wboth));
  PetscFunctionReturn(0);
}
