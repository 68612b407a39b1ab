/* kergs scene ghosts: the distributed disk state (docs/design.md: parallel layout).

   Rank p owns the disks of global indices [dstart, dend), stored first in its local arrays; ghosts follow them:
   copies of the disks of other ranks that may touch an owned disk before the next rebuild of the layer.

   Which disks are ghosts: every rank publishes the bounding box of its owned centres (one all-gather of a few
   reals per rank); a disk is sent as a ghost to every other rank whose box, widened by the reach
   2 max(R) + margin, margin = alert + skin at the build, holds its centre. For two disks a (rank p) and b (rank q)
   within the current alert distance of each other after both moved at most dmax, with alert + 2 dmax <= margin (the
   rebuild rule below), |x_a - x_b| < R_a + R_b + alert + 2 dmax <= R_a + R_b + margin at the build, so b
   is a ghost on p and a a ghost on q: each rank sees every pair that involves one of its disks, and the layer is
   symmetric. A box test over-approximates that set: by a thin band for a compact partition, but by much more for
   METIS's irregular parts (10,500 ghosts instead of about 1,000 on biaxial 100k). So the receiving rank keeps only
   the candidates within the reach of one of its owned disks (a cell grid of its owned centres, cells at least the
   reach wide): the same pair argument holds with the distance test, and the layer stays symmetric. It needs no
   global grid.

   Refresh: between rebuilds, the ghosts' positions, orientations and velocities are copied from their owners
   through a PetscSF (roots: owned disks; leaves: ghosts), one neighbour exchange per step. The layer is rebuilt
   once alert + 2 dmax exceeds the build's alert + skin, dmax the largest displacement of a disk since the build (one
   max-reduction per step decides; with the alert of the build, a disk moved more than skin / 2; the automatic alert
   may grow, KergsSceneAdaptAlert), and after a migration. Migration moves whole disk records
   (KergsExchangeRecords). Disk records travel as bytes: the ranks of a run share one binary representation. */
#include <kergs/private/sceneimpl.h>

/* Everything a disk carries. */
typedef struct {
  PetscInt  gidx, id, material;
  PetscReal x[KERGS_DIM], rot[KERGS_NROT], v[KERGS_DIM], omega[KERGS_NROT], radius, mass, inertia;
} DiskRecord;

/* What moves every step: x, rot, v, omega. */
#define KERGS_DISK_STATE (2 * KERGS_DIM + 2 * KERGS_NROT)

static void PackDisk(KergsScene sc, PetscInt i, DiskRecord *r)
{
  r->gidx     = sc->gidx[i];
  r->id       = sc->id[i];
  r->material = sc->material[i];
  r->radius   = sc->radius[i];
  r->mass     = sc->mass[i];
  r->inertia  = sc->inertia[i];
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    r->x[d] = sc->x[KERGS_DIM * i + d];
    r->v[d] = sc->v[KERGS_DIM * i + d];
  }
  for (PetscInt d = 0; d < KERGS_NROT; d++) {
    r->rot[d]   = sc->rot[KERGS_NROT * i + d];
    r->omega[d] = sc->omega[KERGS_NROT * i + d];
  }
}

static void UnpackDisk(KergsScene sc, PetscInt i, const DiskRecord *r)
{
  sc->gidx[i]     = r->gidx;
  sc->id[i]       = r->id;
  sc->material[i] = r->material;
  sc->radius[i]   = r->radius;
  sc->mass[i]     = r->mass;
  sc->inertia[i]  = r->inertia;
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    sc->x[KERGS_DIM * i + d] = r->x[d];
    sc->v[KERGS_DIM * i + d] = r->v[d];
  }
  for (PetscInt d = 0; d < KERGS_NROT; d++) {
    sc->rot[KERGS_NROT * i + d]   = r->rot[d];
    sc->omega[KERGS_NROT * i + d] = r->omega[d];
  }
}

/* ------------------------------------------------------------------------------------------------ */
/* Ghost layer                                                                                      */

/* The skin actually used: -ghost_skin, or the alert distance, or a tenth of the largest radius when both are 0. */
static PetscReal GhostSkin(KergsScene sc, PetscReal rmax)
{
  if (sc->ghost_skin >= 0.0) return sc->ghost_skin;
  return sc->alert > 0.0 ? sc->alert : 0.1 * rmax;
}

/* Per rank, gathered everywhere: bounding box of the owned centres lo, hi (empty: lo > hi) and dstart. */
#define KERGS_BOX_FIELDS (2 * KERGS_DIM + 1)

static PetscErrorCode GatherBoxes(KergsScene sc, PetscReal **boxes, PetscReal *rmax)
{
  PetscMPIInt size;
  PetscReal   mine[KERGS_BOX_FIELDS], r = 0.0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(sc->comm, &size));
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    mine[d]             = PETSC_MAX_REAL;
    mine[KERGS_DIM + d] = -PETSC_MAX_REAL;
  }
  for (PetscInt i = 0; i < sc->nowned; i++) {
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      mine[d]             = PetscMin(mine[d], sc->x[KERGS_DIM * i + d]);
      mine[KERGS_DIM + d] = PetscMax(mine[KERGS_DIM + d], sc->x[KERGS_DIM * i + d]);
    }
    r = PetscMax(r, sc->radius[i]);
  }
  mine[2 * KERGS_DIM] = (PetscReal)sc->dstart;
  PetscCall(PetscMalloc1(KERGS_BOX_FIELDS * size, boxes));
  PetscCallMPI(MPI_Allgather(mine, KERGS_BOX_FIELDS, MPIU_REAL, *boxes, KERGS_BOX_FIELDS, MPIU_REAL, sc->comm));
  PetscCall(MPIU_Allreduce(&r, rmax, 1, MPIU_REAL, MPIU_MAX, sc->comm));
  PetscFunctionReturn(0);
}

static inline PetscBool InWidenedBox(const PetscReal *box, const PetscReal x[], PetscReal reach)
{
  for (PetscInt d = 0; d < KERGS_DIM; d++)
    if (!(x[d] >= box[d] - reach && x[d] <= box[KERGS_DIM + d] + reach)) return PETSC_FALSE;
  return PETSC_TRUE;
}

/* Records of the owned disks that other ranks need as ghosts, grouped by destination rank. */
static PetscErrorCode SelectGhostsToSend(KergsScene sc, const PetscReal *boxes, PetscReal reach, PetscMPIInt count[], DiskRecord **send)
{
  PetscMPIInt size, rank;
  PetscInt    total = 0, *offset;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(sc->comm, &size));
  PetscCallMPI(MPI_Comm_rank(sc->comm, &rank));
  PetscCall(PetscArrayzero(count, size));
  for (PetscMPIInt q = 0; q < size; q++) {
    if (q == rank) continue;
    for (PetscInt i = 0; i < sc->nowned; i++) count[q] += InWidenedBox(&boxes[KERGS_BOX_FIELDS * q], &sc->x[KERGS_DIM * i], reach);
    total += count[q];
  }
  PetscCall(PetscMalloc1(total + 1, send));
  PetscCall(PetscMalloc1(size + 1, &offset));
  offset[0] = 0;
  for (PetscMPIInt q = 0; q < size; q++) offset[q + 1] = offset[q] + count[q];
  for (PetscMPIInt q = 0; q < size; q++) {
    if (q == rank) continue;
    for (PetscInt i = 0; i < sc->nowned; i++)
      if (InWidenedBox(&boxes[KERGS_BOX_FIELDS * q], &sc->x[KERGS_DIM * i], reach)) PackDisk(sc, i, &(*send)[offset[q]++]);
  }
  PetscCall(PetscFree(offset));
  PetscFunctionReturn(0);
}

/* The SF that refreshes the ghosts: leaf k (ghost nowned + k) reads root gidx - dstart(owner) on its owner. */
static PetscErrorCode BuildGhostSF(KergsScene sc, const PetscReal *boxes)
{
  const PetscInt nghosts = sc->nlocal - sc->nowned;
  PetscSFNode   *remote;

  PetscFunctionBeginUser;
  PetscCall(PetscSFDestroy(&sc->ghost_sf));
  PetscCall(PetscMalloc1(nghosts + 1, &remote));
  for (PetscInt k = 0; k < nghosts; k++) {
    const PetscInt owner = sc->ghost_owner[k];
    remote[k].rank       = owner;
    remote[k].index      = sc->gidx[sc->nowned + k] - (PetscInt)boxes[KERGS_BOX_FIELDS * owner + 2 * KERGS_DIM];
  }
  PetscCall(PetscSFCreate(sc->comm, &sc->ghost_sf));
  PetscCall(PetscSFSetGraph(sc->ghost_sf, sc->nowned, nghosts, NULL, PETSC_OWN_POINTER, remote, PETSC_OWN_POINTER));
  PetscCall(PetscSFSetUp(sc->ghost_sf));
  PetscFunctionReturn(0);
}

/* Cell grid of the owned centres (cells of side >= reach, at most about 4 per owned disk): head[cell] is the first
   owned disk of the cell (-1: none), next[i] the following one. */
typedef struct {
  PetscReal lo[KERGS_DIM], side;
  PetscInt  n[KERGS_DIM], *head, *next;
} OwnedGrid;

static PetscInt GridCoordinate(const OwnedGrid *g, PetscInt d, PetscReal x)
{
  PetscReal c = PetscFloorReal((x - g->lo[d]) / g->side);
  return c < 0 ? -1 : (c >= g->n[d] ? g->n[d] : (PetscInt)c); /* -1 and n: outside the grid */
}

static PetscErrorCode OwnedGridCreate(KergsScene sc, const PetscReal *box, PetscReal reach, OwnedGrid *g)
{
  PetscReal area  = 1.0;
  PetscInt  ncell = 1;

  PetscFunctionBeginUser;
  g->side = reach;
  for (PetscInt d = 0; d < KERGS_DIM; d++) area *= PetscMax(box[KERGS_DIM + d] - box[d], reach);
  if (area / PetscPowRealInt(g->side, KERGS_DIM) > 4.0 * sc->nowned + 16)
    g->side = PetscPowReal(area / (4.0 * sc->nowned + 16), 1.0 / KERGS_DIM);
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    g->lo[d] = box[d];
    g->n[d]  = 1 + (PetscInt)((box[KERGS_DIM + d] - box[d]) / g->side);
    ncell *= g->n[d];
  }
  PetscCall(PetscMalloc2(ncell, &g->head, sc->nowned + 1, &g->next));
  for (PetscInt c = 0; c < ncell; c++) g->head[c] = -1;
  for (PetscInt i = 0; i < sc->nowned; i++) {
    PetscInt c = 0;
    for (PetscInt d = KERGS_DIM - 1; d >= 0; d--) c = c * g->n[d] + GridCoordinate(g, d, sc->x[KERGS_DIM * i + d]);
    g->next[i] = g->head[c];
    g->head[c] = i;
  }
  PetscFunctionReturn(0);
}

/* Whether the centre x is within reach of an owned centre (2D: the 3 x 3 cells around x's). */
static PetscBool NearOwned(KergsScene sc, const OwnedGrid *g, const PetscReal x[], PetscReal reach)
{
  const PetscInt cx = GridCoordinate(g, 0, x[0]), cy = GridCoordinate(g, 1, x[1]);

  for (PetscInt j = PetscMax(cy - 1, 0); j <= PetscMin(cy + 1, g->n[1] - 1); j++)
    for (PetscInt i = PetscMax(cx - 1, 0); i <= PetscMin(cx + 1, g->n[0] - 1); i++)
      for (PetscInt k = g->head[j * g->n[0] + i]; k >= 0; k = g->next[k]) {
        PetscReal d2 = 0.0;
        for (PetscInt d = 0; d < KERGS_DIM; d++) d2 += (x[d] - sc->x[KERGS_DIM * k + d]) * (x[d] - sc->x[KERGS_DIM * k + d]);
        if (d2 <= reach * reach) return PETSC_TRUE;
      }
  return PETSC_FALSE;
}

/* Keep the received candidates within reach of an owned disk, in their order; recvcount[q] and *nrecv follow. */
static PetscErrorCode KeepNearCandidates(KergsScene sc, const PetscReal *box, PetscReal reach, PetscMPIInt size, PetscMPIInt recvcount[],
                                         DiskRecord *recv, PetscInt *nrecv)
{
  OwnedGrid g;
  PetscInt  k = 0, kept = 0;

  PetscFunctionBeginUser;
  if (!sc->nowned) { /* nothing to touch */
    for (PetscMPIInt q = 0; q < size; q++) recvcount[q] = 0;
    *nrecv = 0;
    PetscFunctionReturn(0);
  }
  PetscCall(OwnedGridCreate(sc, box, reach, &g));
  for (PetscMPIInt q = 0; q < size; q++) {
    PetscMPIInt n = 0;
    for (PetscMPIInt j = 0; j < recvcount[q]; j++, k++)
      if (NearOwned(sc, &g, recv[k].x, reach)) {
        recv[kept++] = recv[k];
        n++;
      }
    recvcount[q] = n;
  }
  *nrecv = kept;
  PetscCall(PetscFree2(g.head, g.next));
  PetscFunctionReturn(0);
}

static PetscErrorCode RebuildGhosts(KergsScene sc)
{
  PetscMPIInt size, *sendcount, *recvcount;
  PetscReal  *boxes, rmax = 0.0, reach;
  DiskRecord *send, *recv;
  PetscInt    nrecv;
  PetscMPIInt rank;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(sc->comm, &size));
  PetscCallMPI(MPI_Comm_rank(sc->comm, &rank));
  sc->nlocal = sc->nowned;
  PetscCall(GatherBoxes(sc, &boxes, &rmax));
  sc->ghost_margin = sc->alert + GhostSkin(sc, rmax);
  reach            = 2.0 * rmax + sc->ghost_margin;
  PetscCall(PetscMalloc2(size, &sendcount, size, &recvcount));
  PetscCall(SelectGhostsToSend(sc, boxes, reach, sendcount, &send));
  PetscCall(KergsExchangeRecords(sc->comm, sizeof(DiskRecord), sendcount, send, recvcount, &recv, &nrecv));
  PetscCall(KeepNearCandidates(sc, &boxes[KERGS_BOX_FIELDS * rank], reach, size, recvcount, recv, &nrecv));
  PetscCall(KergsSceneReserve(sc, sc->nowned + nrecv));
  PetscCall(PetscFree(sc->ghost_owner));
  PetscCall(PetscMalloc1(nrecv + 1, &sc->ghost_owner));
  /* records arrive by source rank, each rank's in its owned (global index) order: ghosts end up sorted by global index */
  for (PetscMPIInt q = 0, k = 0; q < size; q++)
    for (PetscMPIInt j = 0; j < recvcount[q]; j++, k++) {
      UnpackDisk(sc, sc->nowned + k, &recv[k]);
      sc->ghost_owner[k] = q;
    }
  sc->nlocal = sc->nowned + nrecv;
  PetscCall(BuildGhostSF(sc, boxes));
  PetscCall(PetscFree(sc->xref));
  PetscCall(PetscMalloc1(KERGS_DIM * sc->nowned + 1, &sc->xref));
  PetscCall(PetscArraycpy(sc->xref, sc->x, KERGS_DIM * sc->nowned));
  sc->ghost_rebuilds++;
  PetscCall(PetscFree2(sendcount, recvcount));
  PetscCall(PetscFree(send));
  PetscCall(PetscFree(recv));
  PetscCall(PetscFree(boxes));
  PetscCall(PetscInfo(NULL, "Scene %s: ghost layer %" PetscInt_FMT " built: %" PetscInt_FMT " owned disks, %" PetscInt_FMT " ghosts\n",
                      sc->name, sc->ghost_rebuilds, sc->nowned, sc->nlocal - sc->nowned));
  PetscFunctionReturn(0);
}

/* Copy x, rot, v, omega of every ghost from its owner. */
static PetscErrorCode RefreshGhosts(KergsScene sc)
{
  const PetscInt nghosts = sc->nlocal - sc->nowned;
  PetscReal     *root, *leaf;
  MPI_Datatype   unit;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(KERGS_DISK_STATE * sc->nowned + 1, &root, KERGS_DISK_STATE * nghosts + 1, &leaf));
  for (PetscInt i = 0; i < sc->nowned; i++) {
    PetscReal *s = &root[KERGS_DISK_STATE * i];
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      s[d]                          = sc->x[KERGS_DIM * i + d];
      s[KERGS_DIM + KERGS_NROT + d] = sc->v[KERGS_DIM * i + d];
    }
    for (PetscInt d = 0; d < KERGS_NROT; d++) {
      s[KERGS_DIM + d]                  = sc->rot[KERGS_NROT * i + d];
      s[2 * KERGS_DIM + KERGS_NROT + d] = sc->omega[KERGS_NROT * i + d];
    }
  }
  PetscCallMPI(MPI_Type_contiguous(KERGS_DISK_STATE, MPIU_REAL, &unit));
  PetscCallMPI(MPI_Type_commit(&unit));
  PetscCall(PetscSFBcastBegin(sc->ghost_sf, unit, root, leaf, MPI_REPLACE));
  PetscCall(PetscSFBcastEnd(sc->ghost_sf, unit, root, leaf, MPI_REPLACE));
  PetscCallMPI(MPI_Type_free(&unit));
  for (PetscInt k = 0; k < nghosts; k++) {
    const PetscReal *s = &leaf[KERGS_DISK_STATE * k];
    const PetscInt   i = sc->nowned + k;
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      sc->x[KERGS_DIM * i + d] = s[d];
      sc->v[KERGS_DIM * i + d] = s[KERGS_DIM + KERGS_NROT + d];
    }
    for (PetscInt d = 0; d < KERGS_NROT; d++) {
      sc->rot[KERGS_NROT * i + d]   = s[KERGS_DIM + d];
      sc->omega[KERGS_NROT * i + d] = s[2 * KERGS_DIM + KERGS_NROT + d];
    }
  }
  PetscCall(PetscFree2(root, leaf));
  PetscFunctionReturn(0);
}

/* Largest displacement of an owned disk since the layer was built, and largest radius, over all ranks (one
   reduction). */
static PetscErrorCode MaxDisplacement(KergsScene sc, PetscReal *dmax, PetscReal *rmax)
{
  PetscReal m[2] = {0.0, 0.0}; /* squared displacement, radius */

  PetscFunctionBeginUser;
  for (PetscInt i = 0; i < sc->nowned; i++) {
    PetscReal d2 = 0.0;
    for (PetscInt d = 0; d < KERGS_DIM; d++) d2 += PetscSqr(sc->x[KERGS_DIM * i + d] - sc->xref[KERGS_DIM * i + d]);
    m[0] = PetscMax(m[0], d2);
    m[1] = PetscMax(m[1], sc->radius[i]);
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, m, 2, MPIU_REAL, MPIU_MAX, sc->comm));
  *dmax = PetscSqrtReal(m[0]);
  *rmax = m[1];
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneUpdateGhosts(KergsScene sc, PetscBool rebuild)
{
  PetscMPIInt size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(sc->comm, &size));
  if (size == 1) { /* one rank owns every disk: no ghosts, nothing to exchange */
    sc->nlocal = sc->nowned;
    PetscFunctionReturn(0);
  }
  PetscCall(PetscLogEventBegin(KERGS_Exchange, 0, 0, 0, 0));
  if (!rebuild && sc->ghost_sf) { /* a layer exists on every rank, or on none (migration and SetDisks drop it everywhere) */
    PetscReal dmax = 0.0, rmax = 0.0;
    PetscCall(MaxDisplacement(sc, &dmax, &rmax));
    rebuild = (PetscBool)(sc->alert + 2.0 * dmax > sc->ghost_margin);
  } else
    rebuild = PETSC_TRUE;
  if (rebuild) PetscCall(RebuildGhosts(sc));
  PetscCall(PetscLogEventEnd(KERGS_Exchange, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneRefreshGhosts(KergsScene sc)
{
  PetscFunctionBeginUser;
  if (!sc->ghost_sf) PetscFunctionReturn(0); /* one rank, or no layer yet (collectively: the same on every rank) */
  PetscCall(PetscLogEventBegin(KERGS_Exchange, 0, 0, 0, 0));
  PetscCall(RefreshGhosts(sc));
  PetscCall(PetscLogEventEnd(KERGS_Exchange, 0, 0, 0, 0));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Checkpoints                                                                                      */

PetscErrorCode KergsSceneGetGhostState(KergsScene sc, PetscBool *layer, const PetscReal **xref, PetscReal *margin, PetscInt *rebuilds)
{
  PetscFunctionBeginUser;
  if (margin) *margin = sc->ghost_margin;
  if (layer) *layer = sc->ghost_sf ? PETSC_TRUE : PETSC_FALSE;
  if (xref) *xref = sc->ghost_sf ? sc->xref : NULL;
  if (rebuilds) *rebuilds = sc->ghost_rebuilds;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneRestoreGhosts(KergsScene sc, PetscBool layer, PetscInt nghosts, const PetscInt gidx[], const PetscReal xref[],
                                       PetscReal margin, PetscInt rebuilds)
{
  PetscMPIInt  size;
  PetscInt    *ranges, mine[2] = {sc->dstart, sc->dend}, *all;
  PetscSFNode *remote;
  DiskRecord  *root, *leaf;
  MPI_Datatype unit;

  PetscFunctionBeginUser;
  sc->ghost_rebuilds = rebuilds;
  sc->ghost_margin   = margin;
  if (margin < 0) { /* a checkpoint without it: the alert (fixed then) plus the skin */
    PetscReal rmax = 0.0;
    for (PetscInt i = 0; i < sc->nowned; i++) rmax = PetscMax(rmax, sc->radius[i]);
    PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &rmax, 1, MPIU_REAL, MPIU_MAX, sc->comm));
    sc->ghost_margin = sc->alert + GhostSkin(sc, rmax);
  }
  PetscCall(PetscSFDestroy(&sc->ghost_sf));
  sc->nlocal = sc->nowned;
  PetscCallMPI(MPI_Comm_size(sc->comm, &size));
  if (size == 1 || !layer) PetscFunctionReturn(0);
  PetscCall(PetscMalloc2(size + 1, &ranges, 2 * size, &all));
  PetscCallMPI(MPI_Allgather(mine, 2, MPIU_INT, all, 2, MPIU_INT, sc->comm));
  for (PetscMPIInt q = 0; q < size; q++) ranges[q] = all[2 * q];
  ranges[size] = sc->ndisks;
  PetscCall(KergsSceneReserve(sc, sc->nowned + nghosts));
  PetscCall(PetscFree(sc->ghost_owner));
  PetscCall(PetscMalloc1(nghosts + 1, &sc->ghost_owner));
  PetscCall(PetscMalloc1(nghosts + 1, &remote));
  for (PetscInt k = 0; k < nghosts; k++) {
    PetscCheck(gidx[k] >= 0 && gidx[k] < sc->ndisks && (gidx[k] < sc->dstart || gidx[k] >= sc->dend), PETSC_COMM_SELF,
               PETSC_ERR_ARG_OUTOFRANGE,
               "Scene %s: ghost %" PetscInt_FMT " of the checkpoint is disk %" PetscInt_FMT ", not another rank's", sc->name, k, gidx[k]);
    sc->ghost_owner[k] = KergsRangeOwner(ranges, size, gidx[k]);
    remote[k].rank     = sc->ghost_owner[k];
    remote[k].index    = gidx[k] - ranges[sc->ghost_owner[k]];
  }
  PetscCall(PetscSFCreate(sc->comm, &sc->ghost_sf));
  PetscCall(PetscSFSetGraph(sc->ghost_sf, sc->nowned, nghosts, NULL, PETSC_OWN_POINTER, remote, PETSC_OWN_POINTER));
  PetscCall(PetscSFSetUp(sc->ghost_sf));
  /* every field of the ghosts from their owners, as a rebuild of the layer copies them */
  PetscCall(PetscMalloc2(sc->nowned + 1, &root, nghosts + 1, &leaf));
  for (PetscInt i = 0; i < sc->nowned; i++) PackDisk(sc, i, &root[i]);
  PetscCallMPI(MPI_Type_contiguous((PetscMPIInt)sizeof(DiskRecord), MPI_BYTE, &unit));
  PetscCallMPI(MPI_Type_commit(&unit));
  PetscCall(PetscSFBcastBegin(sc->ghost_sf, unit, root, leaf, MPI_REPLACE));
  PetscCall(PetscSFBcastEnd(sc->ghost_sf, unit, root, leaf, MPI_REPLACE));
  PetscCallMPI(MPI_Type_free(&unit));
  for (PetscInt k = 0; k < nghosts; k++) UnpackDisk(sc, sc->nowned + k, &leaf[k]);
  sc->nlocal = sc->nowned + nghosts;
  PetscCall(PetscFree(sc->xref));
  PetscCall(PetscMalloc1(KERGS_DIM * sc->nowned + 1, &sc->xref));
  PetscCall(PetscArraycpy(sc->xref, xref, KERGS_DIM * sc->nowned));
  PetscCall(PetscFree2(root, leaf));
  PetscCall(PetscFree2(ranges, all));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Migration                                                                                        */

PetscErrorCode KergsSceneMigrate(KergsScene sc, const PetscInt newidx[], const PetscInt counts[])
{
  PetscMPIInt size, rank, *sendcount, *recvcount;
  PetscInt   *ranges, *offset, nrecv;
  DiskRecord *send, *recv;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(sc->comm, &size));
  PetscCallMPI(MPI_Comm_rank(sc->comm, &rank));
  PetscCall(PetscMalloc2(size + 1, &ranges, size + 1, &offset));
  PetscCall(PetscMalloc2(size, &sendcount, size, &recvcount));
  ranges[0] = 0;
  for (PetscMPIInt q = 0; q < size; q++) ranges[q + 1] = ranges[q] + counts[q];
  PetscCheck(ranges[size] == sc->ndisks, sc->comm, PETSC_ERR_ARG_WRONG,
             "Migration of scene %s: the ranks get %" PetscInt_FMT " disks, not %" PetscInt_FMT, sc->name, ranges[size], sc->ndisks);
  PetscCall(PetscArrayzero(sendcount, size));
  for (PetscInt i = 0; i < sc->nowned; i++) {
    PetscCheck(newidx[i] >= 0 && newidx[i] < sc->ndisks, PETSC_COMM_SELF, PETSC_ERR_ARG_OUTOFRANGE,
               "Migration of scene %s: disk %" PetscInt_FMT " gets global index %" PetscInt_FMT ", outside [0, %" PetscInt_FMT ")",
               sc->name, sc->dstart + i, newidx[i], sc->ndisks);
    sendcount[KergsRangeOwner(ranges, size, newidx[i])]++;
  }
  offset[0] = 0;
  for (PetscMPIInt q = 0; q < size; q++) offset[q + 1] = offset[q] + sendcount[q];
  PetscCall(PetscMalloc1(sc->nowned + 1, &send));
  for (PetscInt i = 0; i < sc->nowned; i++) {
    DiskRecord *r = &send[offset[KergsRangeOwner(ranges, size, newidx[i])]++];
    PackDisk(sc, i, r);
    r->gidx = newidx[i];
  }
  PetscCall(KergsExchangeRecords(sc->comm, sizeof(DiskRecord), sendcount, send, recvcount, &recv, &nrecv));
  PetscCheck(nrecv == counts[rank], PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
             "Migration of scene %s: rank %d received %" PetscInt_FMT " disks, expected %" PetscInt_FMT " (newidx is not a permutation)",
             sc->name, rank, nrecv, counts[rank]);
  /* drop the ghost layer: its disks and its SF describe the old ownership */
  PetscCall(PetscSFDestroy(&sc->ghost_sf));
  sc->dstart = ranges[rank];
  sc->dend   = ranges[rank + 1];
  sc->nowned = sc->nlocal = nrecv;
  PetscCall(KergsSceneReserve(sc, PetscMax(nrecv, 1)));
  for (PetscInt i = 0; i < nrecv; i++) sc->gidx[i] = -1;
  for (PetscInt k = 0; k < nrecv; k++) {
    const PetscInt i = recv[k].gidx - sc->dstart;
    PetscCheck(i >= 0 && i < nrecv && sc->gidx[i] < 0, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONG,
               "Migration of scene %s: global index %" PetscInt_FMT
               " received twice or outside rank %d's range (newidx is not a permutation)",
               sc->name, recv[k].gidx, rank);
    UnpackDisk(sc, i, &recv[k]);
  }
  PetscCall(PetscFree2(ranges, offset));
  PetscCall(PetscFree2(sendcount, recvcount));
  PetscCall(PetscFree(send));
  PetscCall(PetscFree(recv));
  PetscFunctionReturn(0);
}

/* ------------------------------------------------------------------------------------------------ */
/* Gathers for tests and tools                                                                      */

static PetscErrorCode AllGather(KergsScene sc, const void *owned, PetscInt bs, MPI_Datatype type, void *all)
{
  PetscMPIInt size, mine = (PetscMPIInt)(bs * sc->nowned), *counts, *displs;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(sc->comm, &size));
  PetscCall(PetscMalloc2(size, &counts, size, &displs));
  PetscCallMPI(MPI_Allgather(&mine, 1, MPI_INT, counts, 1, MPI_INT, sc->comm));
  displs[0] = 0;
  for (PetscMPIInt q = 1; q < size; q++) displs[q] = displs[q - 1] + counts[q - 1];
  PetscCheck(displs[size - 1] + counts[size - 1] == bs * sc->ndisks, sc->comm, PETSC_ERR_PLIB,
             "Scene %s: the ranks own %d values, not %" PetscInt_FMT, sc->name, displs[size - 1] + counts[size - 1], bs * sc->ndisks);
  /* ranks own increasing ranges of global indices: rank order is global-index order */
  PetscCallMPI(MPI_Allgatherv((void *)owned, mine, type, all, counts, displs, type, sc->comm));
  PetscCall(PetscFree2(counts, displs));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneAllGatherReal(KergsScene sc, const PetscReal owned[], PetscInt bs, PetscReal all[])
{
  PetscFunctionBeginUser;
  PetscCall(AllGather(sc, owned, bs, MPIU_REAL, all));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsSceneAllGatherInt(KergsScene sc, const PetscInt owned[], PetscInt bs, PetscInt all[])
{
  PetscFunctionBeginUser;
  PetscCall(AllGather(sc, owned, bs, MPIU_INT, all));
  PetscFunctionReturn(0);
}
