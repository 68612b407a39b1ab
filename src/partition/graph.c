/* kergs partition, the computation of a new partition (src/partition/partition.c decides when, and migrates the
   disks): the grain graph gathered on rank 0 (vertices: grains with work 1 + contacts, their centres and ids; edges:
   disk-disk contacts) and the algorithms that cut it there, serially: the Hilbert order of the centres, the geometric
   partition along it, METIS k-way on the graph, the relabelling of the parts against the current ownership and the
   new order of the disks, part after part (O(ndisks) memory on rank 0 at each partition, the only such place; at
   hundreds of ranks ParMETIS and a parallel sort would replace them). */
#include <kergs/private/partitionimpl.h>
#include <metis.h>
#include <stdint.h>

/* Side of the Hilbert-curve grid: 2^16 cells, keys below 2^32. */
#define KERGS_HILBERT_ORDER 16

/* The grain graph on rank 0: CSR adjacency of the disk-disk contacts and the work of each grain. */
typedef struct {
  PetscInt   n, nedges;
  PetscInt  *xadj, *adj; /* n + 1, 2 nedges */
  PetscInt  *work;       /* per grain: 1 + ContactWork of its contacts (disk-disk and disk-wall) */
  PetscReal *x;          /* centres (KERGS_DIM per grain) */
  PetscInt  *id;         /* grain ids */
} GrainGraph;

static PetscErrorCode GrainGraphDestroy(GrainGraph *g)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree3(g->xadj, g->adj, g->work));
  PetscCall(PetscFree2(g->x, g->id));
  PetscFunctionReturn(0);
}

/* Centres and ids of every disk, in global-index order, on rank 0. */
static PetscErrorCode GatherGrains(KergsScene sc, GrainGraph *g)
{
  KergsDisks  D;
  MPI_Comm    sccomm;
  PetscMPIInt rank, size, *counts = NULL, *displs = NULL, mine;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  mine = (PetscMPIInt)D.nowned;
  PetscCall(KergsSceneGetComm(sc, &sccomm));
  PetscCallMPI(MPI_Comm_rank(sccomm, &rank));
  PetscCallMPI(MPI_Comm_size(sccomm, &size));
  if (rank == 0) PetscCall(PetscMalloc2(size, &counts, size, &displs));
  PetscCall(PetscMalloc2(rank == 0 ? KERGS_DIM * D.ndisks + 1 : 1, &g->x, rank == 0 ? D.ndisks + 1 : 1, &g->id));
  PetscCallMPI(MPI_Gather(&mine, 1, MPI_INT, counts, 1, MPI_INT, 0, sccomm));
  if (rank == 0) {
    displs[0] = 0;
    for (PetscMPIInt q = 1; q < size; q++) displs[q] = displs[q - 1] + counts[q - 1];
  }
  PetscCallMPI(MPI_Gatherv(D.id, mine, MPIU_INT, g->id, counts, displs, MPIU_INT, 0, sccomm));
  if (rank == 0)
    for (PetscMPIInt q = 0; q < size; q++) {
      counts[q] *= KERGS_DIM;
      displs[q] *= KERGS_DIM;
    }
  mine *= KERGS_DIM;
  PetscCallMPI(MPI_Gatherv(D.x, mine, MPIU_REAL, g->x, counts, displs, MPIU_REAL, 0, sccomm));
  if (rank == 0) PetscCall(PetscFree2(counts, displs));
  PetscFunctionReturn(0);
}

/* Gather every rank's contacts as triples of global indices (a, b) (b = -1 for a wall) and work, the centres and
   the ids to rank 0 and build the graph there. */
static PetscErrorCode GatherGrainGraph(KergsPartition p, KergsScene sc, KergsContacts ct, GrainGraph *g)
{
  PetscInt      nct;
  KergsContact *cts;
  KergsDisks    D;
  const char   *scname;
  MPI_Comm      sccomm;
  PetscMPIInt   rank, size, nmine, *counts = NULL, *displs = NULL;
  PetscInt     *mine, *all = NULL, nall = 0, *fill;
  KergsActivity act;

  PetscFunctionBeginUser;
  PetscCall(KergsContactsGetLocal(ct, &nct, &cts));
  PetscCall(KergsContactsGetActivity(ct, sc, &act));
  nmine = (PetscMPIInt)(3 * nct);
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetName(sc, &scname));
  PetscCall(KergsSceneGetComm(sc, &sccomm));
  PetscCallMPI(MPI_Comm_rank(sccomm, &rank));
  PetscCallMPI(MPI_Comm_size(sccomm, &size));
  PetscCall(PetscMemzero(g, sizeof(*g)));
  PetscCall(PetscMalloc1(nmine + 1, &mine));
  for (PetscInt k = 0; k < nct; k++) {
    PetscCheck(cts[k].kind != KERGS_CONTACT_DISK_DISK || (cts[k].b >= 0 && cts[k].b < D.nlocal), PETSC_COMM_SELF, PETSC_ERR_ARG_WRONGSTATE,
               "Scene %s: contact %" PetscInt_FMT " names local disk %" PetscInt_FMT " of %" PetscInt_FMT, scname, k, cts[k].b, D.nlocal);
    mine[3 * k]     = D.gidx[cts[k].a];
    mine[3 * k + 1] = cts[k].kind == KERGS_CONTACT_DISK_DISK ? D.gidx[cts[k].b] : -1;
    /* measured work: the model in tenths, times this rank's factor (time per modelled unit, relative to the mean) */
    mine[3 * k + 2] = p->work == KERGS_PARTITION_WORK_MEASURED
                          ? PetscMax(1, (PetscInt)(10.0 * p->state.work_scale * KergsPartitionContactWork(&act, &cts[k]) + 0.5))
                          : KergsPartitionContactWork(&act, &cts[k]);
  }
  PetscCall(GatherGrains(sc, g));
  if (rank == 0) PetscCall(PetscMalloc2(size, &counts, size, &displs));
  PetscCallMPI(MPI_Gather(&nmine, 1, MPI_INT, counts, 1, MPI_INT, 0, sccomm));
  if (rank == 0) {
    for (PetscMPIInt q = 0; q < size; q++) {
      displs[q] = (PetscMPIInt)nall;
      nall += counts[q];
    }
  }
  PetscCall(PetscMalloc1(nall + 1, &all));
  PetscCallMPI(MPI_Gatherv(mine, nmine, MPIU_INT, all, counts, displs, MPIU_INT, 0, sccomm));
  PetscCall(PetscFree(mine));
  if (rank == 0) {
    const PetscInt n = D.ndisks;

    g->n = n;
    for (PetscInt k = 0; k < nall / 3; k++) g->nedges += all[3 * k + 1] >= 0;
    PetscCall(PetscCalloc3(n + 1, &g->xadj, 2 * g->nedges + 1, &g->adj, n + 1, &g->work));
    for (PetscInt i = 0; i < n; i++) g->work[i] = 1;
    for (PetscInt k = 0; k < nall / 3; k++) {
      const PetscInt a = all[3 * k], b = all[3 * k + 1];
      PetscCheck(a >= 0 && a < n && b < n, PETSC_COMM_SELF, PETSC_ERR_PLIB,
                 "Contact (%" PetscInt_FMT ", %" PetscInt_FMT ") outside the %" PetscInt_FMT " disks of scene %s", a, b, n, scname);
      g->work[a] += all[3 * k + 2];
      if (b < 0) continue;
      g->work[b] += all[3 * k + 2];
      g->xadj[a + 1]++;
      g->xadj[b + 1]++;
    }
    for (PetscInt i = 0; i < n; i++) g->xadj[i + 1] += g->xadj[i];
    PetscCall(PetscMalloc1(n + 1, &fill));
    PetscCall(PetscArraycpy(fill, g->xadj, n));
    for (PetscInt k = 0; k < nall / 3; k++) {
      const PetscInt a = all[3 * k], b = all[3 * k + 1];
      if (b < 0) continue;
      g->adj[fill[a]++] = b;
      g->adj[fill[b]++] = a;
    }
    PetscCall(PetscFree(fill));
    PetscCall(PetscFree2(counts, displs));
  }
  PetscCall(PetscFree(all));
  PetscFunctionReturn(0);
}

/* Index along a Hilbert curve of the cell (x, y) of a 2^KERGS_HILBERT_ORDER grid. At each level the quadrant
   gives two bits of the index (visiting order lower-left, upper-left, upper-right, lower-right), and the cell is
   mapped into the frame of that quadrant's sub-curve: transposed in the first quadrant, transposed and mirrored
   in the last, unchanged in the two upper ones. */
static uint64_t HilbertIndex(uint32_t x, uint32_t y)
{
  uint64_t index = 0;

  for (uint32_t half = 1u << (KERGS_HILBERT_ORDER - 1); half > 0; half >>= 1) {
    const uint32_t right = (x & half) ? 1 : 0, up = (y & half) ? 1 : 0;
    const uint32_t quadrant = right ? (up ? 2 : 3) : (up ? 1 : 0);

    index += (uint64_t)quadrant * half * half;
    x &= half - 1;
    y &= half - 1;
    if (!up) {
      uint32_t t;
      if (right) { /* mirror in the anti-diagonal */
        x = half - 1 - x;
        y = half - 1 - y;
      }
      t = x; /* transpose */
      x = y;
      y = t;
    }
  }
  return index;
}

typedef struct {
  uint64_t key;
  PetscInt disk;
} CurveEntry;

static int CompareCurveEntries(const void *x, const void *y)
{
  const CurveEntry *p = (const CurveEntry *)x, *q = (const CurveEntry *)y;

  if (p->key != q->key) return p->key < q->key ? -1 : 1;
  return p->disk < q->disk ? -1 : (p->disk > q->disk ? 1 : 0);
}

/* seq[k]: the k-th disk along the Hilbert curve of a square grid over the bounding box of the centres (one cell size
   for both axes, so that the curve keeps the packing's aspect); ties by index. */
static PetscErrorCode HilbertOrder(const GrainGraph *g, PetscInt seq[])
{
  const PetscInt   n = g->n;
  const PetscReal *x = g->x;
  PetscReal        lo[KERGS_DIM], hi[KERGS_DIM], extent = 0, scale;
  CurveEntry      *e;

  PetscFunctionBeginUser;
  for (PetscInt d = 0; d < KERGS_DIM; d++) {
    lo[d] = PETSC_MAX_REAL;
    hi[d] = -PETSC_MAX_REAL;
  }
  for (PetscInt i = 0; i < n; i++)
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      lo[d] = PetscMin(lo[d], x[KERGS_DIM * i + d]);
      hi[d] = PetscMax(hi[d], x[KERGS_DIM * i + d]);
    }
  for (PetscInt d = 0; d < KERGS_DIM; d++) extent = PetscMax(extent, hi[d] - lo[d]);
  scale = extent > 0 ? ((PetscReal)((1u << KERGS_HILBERT_ORDER) - 1)) / extent : 0.0;
  PetscCall(PetscMalloc1(n + 1, &e));
  for (PetscInt i = 0; i < n; i++) {
    uint32_t cell[KERGS_DIM];
    for (PetscInt d = 0; d < KERGS_DIM; d++) {
      PetscReal s = (x[KERGS_DIM * i + d] - lo[d]) * scale;
      cell[d]     = (uint32_t)PetscMin(PetscMax(s, 0.0), (PetscReal)((1u << KERGS_HILBERT_ORDER) - 1));
    }
    e[i].key  = HilbertIndex(cell[0], cell[1]);
    e[i].disk = i;
  }
  qsort(e, (size_t)n, sizeof(CurveEntry), CompareCurveEntries);
  for (PetscInt k = 0; k < n; k++) seq[k] = e[k].disk;
  PetscCall(PetscFree(e));
  PetscFunctionReturn(0);
}

/* Geometric partition: the disks along the Hilbert curve (seq, also the order within the parts) cut into nparts
   chunks of equal work; part[i] is the part of disk i. */
static PetscErrorCode GeometricPartition(const GrainGraph *g, const PetscInt work[], PetscInt nparts, PetscInt part[], PetscInt seq[])
{
  const PetscInt n     = g->n;
  PetscReal      total = 0, before = 0;

  PetscFunctionBeginUser;
  PetscCall(HilbertOrder(g, seq));
  for (PetscInt i = 0; i < n; i++) total += (PetscReal)work[i];
  /* the k-th disk goes to the part containing the middle of its work interval [before, before + w) */
  for (PetscInt k = 0; k < n; k++) {
    const PetscInt i = seq[k];
    PetscInt       q = (PetscInt)PetscFloorReal((PetscReal)nparts * (before + 0.5 * work[i]) / total);
    part[i]          = PetscMin(PetscMax(q, 0), nparts - 1);
    before += (PetscReal)work[i];
  }
  PetscFunctionReturn(0);
}

/* METIS k-way on the grain graph, vertex weights = work, fixed seed; returns METIS's status.
   The graph is given to METIS in the order of the grain ids (canon: disks sorted by id), which do not change when
   the disks are renumbered: METIS's answer depends on the vertex order, and this way a graph that changed little
   since the last partition gets a similar partition (few grains move).
   With curve (the disks along the Hilbert curve), consecutive disks along it are also joined, by edges of weight 1
   against KERGS_PARTITION_CONTACT_WEIGHT for a contact: grains or clusters without contacts to the rest (rattlers,
   grains still falling) then go with their spatial neighbours instead of wherever METIS's balancing puts them. */
static PetscErrorCode MetisPartition(const GrainGraph *g, const PetscInt canon[], const PetscInt *curve, PetscInt nparts, PetscInt seed,
                                     PetscInt part[], int *status)
{
  const PetscInt n     = g->n;
  idx_t          nvtxs = (idx_t)n, ncon = 1, np = (idx_t)nparts, objval = 0, options[METIS_NOPTIONS];
  idx_t         *xadj, *adj, *adjw, *vwgt, *mpart;
  PetscInt      *prev, *next, *rank, nz = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc5(n + 1, &xadj, 2 * g->nedges + 2 * n + 1, &adj, 2 * g->nedges + 2 * n + 1, &adjw, n + 1, &vwgt, n + 1, &mpart));
  PetscCall(PetscMalloc3(n + 1, &prev, n + 1, &next, n + 1, &rank));
  for (PetscInt v = 0; v < n; v++) rank[canon[v]] = v; /* METIS vertex of each disk */
  for (PetscInt i = 0; i < n; i++) prev[i] = next[i] = -1;
  for (PetscInt k = 0; curve && k + 1 < n; k++) {
    next[curve[k]]     = curve[k + 1];
    prev[curve[k + 1]] = curve[k];
  }
  for (PetscInt v = 0; v < n; v++) {
    const PetscInt i        = canon[v];
    PetscInt       chain[2] = {prev[i], next[i]};
    xadj[v]                 = (idx_t)nz;
    vwgt[v]                 = (idx_t)g->work[i];
    for (PetscInt k = g->xadj[i]; k < g->xadj[i + 1]; k++) {
      adj[nz]    = (idx_t)rank[g->adj[k]];
      adjw[nz++] = KERGS_PARTITION_CONTACT_WEIGHT;
    }
    for (PetscInt c = 0; c < 2; c++) { /* a curve neighbour that is also a contact keeps the contact's edge only */
      PetscBool dup = PETSC_FALSE;
      if (chain[c] < 0) continue;
      for (PetscInt k = g->xadj[i]; k < g->xadj[i + 1]; k++) dup = (PetscBool)(dup || g->adj[k] == chain[c]);
      if (dup) continue;
      adj[nz]    = (idx_t)rank[chain[c]];
      adjw[nz++] = 1;
    }
  }
  xadj[n] = (idx_t)nz;
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED]      = (idx_t)seed;
  options[METIS_OPTION_NUMBERING] = 0;
  *status = METIS_PartGraphKway(&nvtxs, &ncon, xadj, adj, vwgt, NULL, adjw, &np, NULL, NULL, options, &objval, mpart);
  for (PetscInt v = 0; v < n; v++) part[canon[v]] = (PetscInt)mpart[v];
  for (PetscInt i = 0; *status == METIS_OK && i < n; i++)
    if (part[i] < 0 || part[i] >= nparts) *status = METIS_ERROR;
  PetscCall(PetscFree3(prev, next, rank));
  PetscCall(PetscFree5(xadj, adj, adjw, vwgt, mpart));
  PetscFunctionReturn(0);
}

/* canon[v]: the disk of the v-th smallest grain id (ties, which valid scenes do not have, by index). */
static PetscErrorCode IdOrder(const GrainGraph *g, PetscInt canon[])
{
  PetscInt *ids;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc1(g->n + 1, &ids));
  for (PetscInt i = 0; i < g->n; i++) {
    ids[i]   = g->id[i];
    canon[i] = i;
  }
  PetscCall(PetscSortIntWithArray(g->n, ids, canon));
  PetscCall(PetscFree(ids));
  PetscFunctionReturn(0);
}

typedef struct {
  PetscInt label, rank, overlap;
} LabelOverlap;

static int CompareLabelRank(const void *x, const void *y)
{
  const LabelOverlap *p = (const LabelOverlap *)x, *q = (const LabelOverlap *)y;

  if (p->label != q->label) return p->label < q->label ? -1 : 1;
  return p->rank < q->rank ? -1 : (p->rank > q->rank ? 1 : 0);
}

static int CompareOverlapDesc(const void *x, const void *y)
{
  const LabelOverlap *p = (const LabelOverlap *)x, *q = (const LabelOverlap *)y;

  if (p->overlap != q->overlap) return p->overlap > q->overlap ? -1 : 1;
  return CompareLabelRank(x, y);
}

/* Give each part the rank that already owns most of its grains (greedy matching on the overlaps, largest first),
   so that a new partition close to the current one moves few grains. Parts left over take the free ranks. */
static PetscErrorCode RelabelParts(PetscInt n, PetscInt nparts, const PetscInt oldranges[], PetscInt part[])
{
  LabelOverlap *o;
  PetscInt     *map, *taken, no = 0, nextfree = 0;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc3(n + 1, &o, nparts, &map, nparts, &taken));
  for (PetscInt i = 0; i < n; i++) {
    o[i].label   = part[i];
    o[i].rank    = KergsRangeOwner(oldranges, (PetscMPIInt)nparts, i);
    o[i].overlap = 1;
  }
  qsort(o, (size_t)n, sizeof(LabelOverlap), CompareLabelRank);
  for (PetscInt i = 0; i < n; i++) { /* run lengths: one entry per (label, rank) pair */
    if (no > 0 && o[no - 1].label == o[i].label && o[no - 1].rank == o[i].rank)
      o[no - 1].overlap++;
    else
      o[no++] = o[i];
  }
  qsort(o, (size_t)no, sizeof(LabelOverlap), CompareOverlapDesc);
  for (PetscInt q = 0; q < nparts; q++) map[q] = taken[q] = -1;
  for (PetscInt k = 0; k < no; k++)
    if (map[o[k].label] < 0 && taken[o[k].rank] < 0) {
      map[o[k].label]  = o[k].rank;
      taken[o[k].rank] = o[k].label;
    }
  for (PetscInt q = 0; q < nparts; q++) {
    if (map[q] >= 0) continue;
    while (taken[nextfree] >= 0) nextfree++;
    map[q]          = nextfree;
    taken[nextfree] = q;
  }
  for (PetscInt i = 0; i < n; i++) part[i] = map[part[i]];
  PetscCall(PetscFree3(o, map, taken));
  PetscFunctionReturn(0);
}

/* New order: disks sorted by part, stable in the sequence seq (the order within a part); counts per part. */
static void OrderByPart(PetscInt n, PetscInt nparts, const PetscInt part[], const PetscInt seq[], PetscInt order[], PetscInt counts[])
{
  PetscInt *fill = counts + nparts; /* counts has 2 nparts entries of workspace */

  for (PetscInt q = 0; q < nparts; q++) counts[q] = 0;
  for (PetscInt i = 0; i < n; i++) counts[part[i]]++;
  fill[0] = 0;
  for (PetscInt q = 1; q < nparts; q++) fill[q] = fill[q - 1] + counts[q - 1];
  for (PetscInt k = 0; k < n; k++) order[fill[part[seq[k]]]++] = seq[k];
}

/* max part work / mean part work of the new partition; counts[q] grains in part q, in the new order. */
static PetscErrorCode PartImbalance(const GrainGraph *g, PetscInt nparts, const PetscInt order[], const PetscInt counts[],
                                    PetscReal *imbalance)
{
  PetscReal total = 0, wmax = 0;
  PetscInt  k = 0;

  PetscFunctionBeginUser;
  for (PetscInt q = 0; q < nparts; q++) {
    PetscReal w = 0;
    for (PetscInt end = k + counts[q]; k < end; k++) w += (PetscReal)g->work[order[k]];
    total += w;
    wmax = PetscMax(wmax, w);
  }
  *imbalance = total > 0 ? wmax * nparts / total : 1.0;
  PetscFunctionReturn(0);
}

static PetscInt EdgeCut(const GrainGraph *g, const PetscInt part[])
{
  PetscInt cut = 0;

  for (PetscInt i = 0; i < g->n; i++)
    for (PetscInt k = g->xadj[i]; k < g->xadj[i + 1]; k++) cut += (g->adj[k] > i && part[g->adj[k]] != part[i]);
  return cut;
}

/* The outcome broadcast as PetscInt: method, edgecut, status, metis_tried (the imbalance follows as a PetscReal). */
#define KERGS_OUTCOME_LEN 4

/* part (and seq, the order within the parts) by one method. */
static PetscErrorCode ComputeParts(KergsPartition p, const GrainGraph *g, KergsPartitionType method, PetscMPIInt size, PetscInt part[],
                                   PetscInt seq[], PetscInt *status)
{
  const PetscInt n = g->n;

  PetscFunctionBeginUser;
  *status = METIS_OK;
  for (PetscInt i = 0; i < n; i++) seq[i] = i;
  if (method == KERGS_PARTITION_METIS) {
    int       st = METIS_ERROR;
    PetscInt *canon;
    PetscCall(PetscMalloc1(n + 1, &canon));
    PetscCall(IdOrder(g, canon));
    if (p->metis_curve) PetscCall(HilbertOrder(g, seq)); /* the order within the parts stays the index order */
    PetscCall(MetisPartition(g, canon, p->metis_curve ? seq : NULL, size, p->metis_seed, part, &st));
    PetscCall(PetscFree(canon));
    for (PetscInt i = 0; i < n; i++) seq[i] = i;
    *status = st;
  } else if (method == KERGS_PARTITION_GEOMETRIC) {
    PetscCall(GeometricPartition(g, g->work, size, part, seq));
    /* the parts follow the Hilbert curve, but inside a part the disks keep their index order, as with METIS: the
       Gauss-Seidel order of the sweeps then does not depend on the partition (biaxial 20k on 2 ranks: 7-10 % more
       sweeps per step when each rank swept its contacts along the curve instead of the generator's rows) */
    for (PetscInt i = 0; i < n; i++) seq[i] = i;
  } else {
    for (PetscMPIInt q = 0; q < size; q++) /* the even split of KergsSceneSetDisks: the first n % size ranks get one more */
      for (PetscInt i = q * (n / size) + PetscMin(q, n % size); i < (q + 1) * (n / size) + PetscMin(q + 1, n % size); i++) part[i] = q;
  }
  PetscFunctionReturn(0);
}

/* From part: relabel against the current ownership (not for contiguous), new order, counts, edge cut, imbalance. */
static PetscErrorCode FinishParts(const GrainGraph *g, KergsPartitionType method, PetscMPIInt size, const PetscInt oldranges[],
                                  PetscInt part[], const PetscInt seq[], PetscInt order[], PetscInt counts[], KergsPartitionOutcome *out)
{
  PetscFunctionBeginUser;
  if (method != KERGS_PARTITION_CONTIGUOUS) PetscCall(RelabelParts(g->n, size, oldranges, part));
  OrderByPart(g->n, size, part, seq, order, counts);
  out->method  = method;
  out->status  = METIS_OK;
  out->edgecut = g->nedges > 0 ? EdgeCut(g, part) : -1;
  PetscCall(PartImbalance(g, size, order, counts, &out->imbalance));
  PetscFunctionReturn(0);
}

/* On rank 0: choose the method (METIS needs a dense enough graph and at least as many grains as ranks), compute the
   parts and the new order. METIS can miss the balance on tiny graphs (it may leave a part empty): when its
   imbalance exceeds the tolerance, the geometric partition is taken instead if it is within the tolerance, or if
   METIS left a part empty and the geometric partition does not. */
static PetscErrorCode ComputePartitionOnRoot(KergsPartition p, const GrainGraph *g, const PetscInt oldranges[], PetscMPIInt size,
                                             PetscInt order[], PetscInt counts[], KergsPartitionOutcome *out)
{
  const PetscInt     n      = g->n;
  PetscBool          dense  = (PetscBool)(2.0 * g->nedges >= KERGS_PARTITION_MIN_DEGREE * n && g->nedges > 0);
  KergsPartitionType method = p->type;
  PetscInt          *part, *seq, status;

  PetscFunctionBeginUser;
  PetscCall(PetscMalloc2(n + 1, &part, n + 1, &seq));
  if (method == KERGS_PARTITION_METIS && (!dense || n < size)) method = KERGS_PARTITION_GEOMETRIC;
  PetscCall(ComputeParts(p, g, method, size, part, seq, &status));
  out->method      = method;
  out->status      = status;
  out->metis_tried = method == KERGS_PARTITION_METIS;
  if (status == METIS_OK) PetscCall(FinishParts(g, method, size, oldranges, part, seq, order, counts, out));
  if (status == METIS_OK && method == KERGS_PARTITION_METIS && out->imbalance > p->imbalance_tol) {
    PetscInt             *order2, *counts2;
    KergsPartitionOutcome alt;
    PetscBool             emptymetis = PETSC_FALSE, emptyalt = PETSC_FALSE;

    PetscCall(PetscMalloc2(n + 1, &order2, 2 * size, &counts2));
    PetscCall(ComputeParts(p, g, KERGS_PARTITION_GEOMETRIC, size, part, seq, &status));
    PetscCall(FinishParts(g, KERGS_PARTITION_GEOMETRIC, size, oldranges, part, seq, order2, counts2, &alt));
    alt.metis_tried = PETSC_TRUE;
    for (PetscMPIInt q = 0; q < size; q++) {
      emptymetis = (PetscBool)(emptymetis || counts[q] == 0);
      emptyalt   = (PetscBool)(emptyalt || counts2[q] == 0);
    }
    /* within the tolerance, or METIS left a part empty (tiny graphs) and the geometric split does not */
    if (alt.imbalance <= p->imbalance_tol || (emptymetis && !emptyalt && n >= size)) {
      PetscCall(PetscInfo(NULL, "METIS partition of imbalance %g replaced by the geometric one of imbalance %g\n", (double)out->imbalance,
                          (double)alt.imbalance));
      *out = alt;
      PetscCall(PetscArraycpy(order, order2, n));
      PetscCall(PetscArraycpy(counts, counts2, size));
    }
    PetscCall(PetscFree2(order2, counts2));
  }
  PetscCall(PetscFree2(part, seq));
  PetscFunctionReturn(0);
}

/* Gather the grain graph on rank 0, compute the new order there and tell every rank the outcome and the counts. */
PetscErrorCode KergsPartitionComputeOrder(KergsPartition p, KergsScene sc, KergsContacts ct, const PetscInt oldranges[], PetscInt order[],
                                          PetscInt counts[], KergsPartitionOutcome *out)
{
  KergsDisks  D;
  const char *scname;
  PetscMPIInt rank, size;
  GrainGraph  g;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetName(sc, &scname));
  PetscCallMPI(MPI_Comm_rank(p->comm, &rank));
  PetscCallMPI(MPI_Comm_size(p->comm, &size));
  *out = (KergsPartitionOutcome){KERGS_PARTITION_CONTIGUOUS, -1, METIS_OK, PETSC_FALSE, 1.0};
  PetscCall(GatherGrainGraph(p, sc, ct, &g));
  if (rank == 0) PetscCall(ComputePartitionOnRoot(p, &g, oldranges, size, order, counts, out));
  PetscCall(GrainGraphDestroy(&g));
  {
    PetscInt v[KERGS_OUTCOME_LEN] = {out->method, out->edgecut, out->status, out->metis_tried};
    PetscCallMPI(MPI_Bcast(v, KERGS_OUTCOME_LEN, MPIU_INT, 0, p->comm));
    out->method      = v[0];
    out->edgecut     = v[1];
    out->status      = v[2];
    out->metis_tried = v[3];
  }
  PetscCallMPI(MPI_Bcast(&out->imbalance, 1, MPIU_REAL, 0, p->comm));
  PetscCheck(out->status == METIS_OK, p->comm, PETSC_ERR_LIB,
             "METIS_PartGraphKway failed (status %" PetscInt_FMT ") partitioning the %" PetscInt_FMT " grains of scene %s into %d parts",
             out->status, D.ndisks, scname, size);
  PetscCallMPI(MPI_Bcast(counts, size, MPIU_INT, 0, p->comm));
  PetscFunctionReturn(0);
}
