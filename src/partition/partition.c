/* kergs partition: ownership of the grains by the ranks (docs/design.md: parallel layout).

   Rank p owns the disks of global indices [dstart, dend), so a partition is a new numbering of the disks, part
   after part. It is computed on rank 0 from the grain graph gathered there (vertices: grains with work
   1 + contacts and their centres and ids; edges: disk-disk contacts); each rank receives the new global index of
   its own disks (MPI_Scatterv); the disks then migrate to their new owners with their whole state (KergsSceneMigrate), and the contacts
   follow their disk a with their impulses, so that the next detection warm-starts them (Algorithm 1). METIS and the Hilbert sort run
   serially on rank 0 (O(ndisks) memory there at each partition, the only such place); at hundreds of ranks ParMETIS and a parallel sort
   would replace them. */
#include <kergs/private/partitionimpl.h>
#include <metis.h>
#include <stdint.h>

const char *const KergsPartitionTypes[] = {"contiguous", "geometric", "metis", "KergsPartitionType", "KERGS_PARTITION_", NULL};
const char *const KergsPartitionWorks[] = {"model", "measured", "KergsPartitionWork", "KERGS_PARTITION_WORK_", NULL};

/* Side of the Hilbert-curve grid: 2^16 cells, keys below 2^32. */
#define KERGS_HILBERT_ORDER 16

PetscErrorCode KergsPartitionCreate(MPI_Comm comm, KergsPartition *partition)
{
  KergsPartition p;
  PetscMPIInt    size;

  PetscFunctionBeginUser;
  PetscCall(KergsInitializePackage());
  PetscCallMPI(MPI_Comm_size(comm, &size));
  PetscCall(PetscNew(&p));
  p->comm                 = comm;
  p->type                 = size > 1 ? KERGS_PARTITION_METIS : KERGS_PARTITION_CONTIGUOUS;
  p->imbalance_tol        = 1.10;
  p->edgecut_growth       = 1.25;
  p->check_every          = 10;
  p->metis_seed           = 2013;
  p->metis_curve          = PETSC_TRUE;
  p->state.edgecut_base   = -1;
  p->state.last_method    = KERGS_PARTITION_CONTIGUOUS;
  p->state.imbalance_base = 1.0;
  p->work                 = KERGS_PARTITION_WORK_MODEL;
  p->state.work_scale     = 1.0;
  *partition              = p;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPartitionGetView(KergsPartition p, PetscViewer *viewer)
{
  PetscFunctionBeginUser;
  *viewer = p->viewer;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPartitionSetFromOptions(KergsPartition p)
{
  PetscFunctionBeginUser;
  PetscOptionsBegin(p->comm, NULL, "Partition options (ownership of the grains by the ranks)", NULL);
  PetscCall(PetscOptionsEnum("-partition_type",
                             "contiguous (even split by index, never changed), geometric (Hilbert curve), metis (k-way on the contact "
                             "graph; the default on several ranks; one rank never partitions)",
                             "", KergsPartitionTypes, (PetscEnum)p->type, (PetscEnum *)&p->type, NULL));
  PetscCall(PetscOptionsReal(
      "-partition_imbalance_tol",
      "Repartition when the max rank work / mean work reaches this factor and grew since the last partition (1: at every check)", "",
      p->imbalance_tol, &p->imbalance_tol, NULL));
  PetscCall(PetscOptionsReal("-partition_edgecut_growth",
                             "Repartition when the edge cut exceeds this factor times max(1, the cut right after the last partition)", "",
                             p->edgecut_growth, &p->edgecut_growth, NULL));
  PetscCall(PetscOptionsInt("-partition_check_every", "Steps between two checks of the partition (0: never repartition)", "",
                            p->check_every, &p->check_every, NULL));
  PetscCall(PetscViewerDestroy(&p->viewer));
  PetscCall(PetscOptionsViewer(
      "-partition_view", "Print per step and rank: grains, ghosts, contacts, work, sweep time; and the edge cut (PETSc viewer syntax)",
      "KergsPartitionView", &p->viewer, &p->view_format, NULL));
  PetscCall(PetscOptionsBool(
      "-partition_metis_curve",
      "Join consecutive grains along a Hilbert curve by light edges in METIS's graph (locality for grains without contacts)", "",
      p->metis_curve, &p->metis_curve, NULL));
  PetscCall(PetscOptionsEnum(
      "-partition_work",
      "Work of a rank: measured (its time in the sweeps' arithmetic at the last step, spread over its grains by the model; balances what "
      "the model misses, not reproducible to the bit across runs) or model (active contacts count 6, inactive 1; deterministic)",
      "", KergsPartitionWorks, (PetscEnum)p->work, (PetscEnum *)&p->work, NULL));
  PetscCall(PetscOptionsInt("-partition_metis_seed", "Seed of METIS's random choices (fixed: reproducible partitions)", "", p->metis_seed,
                            &p->metis_seed, NULL));
  PetscOptionsEnd();
  PetscCall(KergsOptionsCheckInt(p->comm, NULL, "-partition_check_every"));
  PetscCall(KergsOptionsCheckInt(p->comm, NULL, "-partition_metis_seed"));
  PetscCheck(p->imbalance_tol >= 1.0 && !PetscIsInfOrNanReal(p->imbalance_tol), p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-partition_imbalance_tol %g must be at least 1 (max work / mean work)", (double)p->imbalance_tol);
  PetscCheck(p->edgecut_growth > 0.0 && !PetscIsInfOrNanReal(p->edgecut_growth), p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-partition_edgecut_growth %g must be positive", (double)p->edgecut_growth);
  PetscCheck(p->check_every >= 0, p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "-partition_check_every %" PetscInt_FMT " must be non-negative (0: never)", p->check_every);
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPartitionDestroy(KergsPartition *p)
{
  PetscFunctionBeginUser;
  if (!p || !*p) PetscFunctionReturn(0);
  PetscCall(PetscViewerDestroy(&(*p)->viewer));
  PetscCall(PetscFree(*p));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPartitionGetState(KergsPartition p, KergsPartitionState *s)
{
  PetscFunctionBeginUser;
  *s = p->state;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPartitionSetState(KergsPartition p, const KergsPartitionState *s)
{
  PetscFunctionBeginUser;
  if (!s) { /* as KergsPartitionCreate leaves it */
    p->state.initialized     = PETSC_FALSE;
    p->state.provisional     = PETSC_FALSE;
    p->state.edgecut_base    = -1;
    p->state.nrepartitions   = 0;
    p->state.nmoved          = 0;
    p->state.last_method     = KERGS_PARTITION_CONTIGUOUS;
    p->state.imbalance_base  = 1.0;
    p->state.compute_seconds = 0.0;
    p->state.work_scale      = 1.0;
    PetscFunctionReturn(0);
  }
  PetscCheck(s->last_method >= KERGS_PARTITION_CONTIGUOUS && s->last_method <= KERGS_PARTITION_METIS, p->comm, PETSC_ERR_ARG_OUTOFRANGE,
             "Partition state: unknown method %" PetscInt_FMT, s->last_method);
  p->state = *s;
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPartitionView(KergsPartition p, PetscViewer viewer)
{
  PetscFunctionBeginUser;
  if (!viewer) PetscCall(PetscViewerASCIIGetStdout(p->comm, &viewer));
  PetscCall(PetscViewerASCIIPrintf(viewer, "Partition: %s, check every %" PetscInt_FMT " steps, imbalance tol %g, edge cut growth %g\n",
                                   KergsPartitionTypes[p->type], p->check_every, (double)p->imbalance_tol, (double)p->edgecut_growth));
  PetscCall(PetscViewerASCIIPushTab(viewer));
  PetscCall(PetscViewerASCIIPrintf(
      viewer, "%" PetscInt_FMT " repartitions after the initial one (latest: %s%s), %" PetscInt_FMT " grains moved in all, %.3g s\n",
      p->state.nrepartitions, KergsPartitionTypes[p->state.last_method], p->state.provisional ? ", provisional" : "", p->state.nmoved,
      (double)p->seconds));
  PetscCall(PetscViewerASCIIPrintf(
      viewer, "latest measures: edge cut %" PetscInt_FMT " of %" PetscInt_FMT " edges, imbalance %.4g, ghosts %" PetscInt_FMT "\n",
      p->last.edgecut, p->last.edges, (double)p->last.imbalance, p->last.ghosts));
  PetscCall(PetscViewerASCIIPopTab(viewer));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* Ownership ranges                                                                                           */

/* ranges[p] .. ranges[p+1]: the disks of rank p (size + 1 entries), checked to tile [0, ndisks) in rank order. */
static PetscErrorCode GetRanges(KergsScene sc, PetscInt **ranges)
{
  KergsDisks  D;
  const char *scname;
  MPI_Comm    sccomm;
  PetscMPIInt size;
  PetscInt    mine[2], *all;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  mine[0] = D.dstart;
  mine[1] = D.dend;
  PetscCall(KergsSceneGetName(sc, &scname));
  PetscCall(KergsSceneGetComm(sc, &sccomm));
  PetscCallMPI(MPI_Comm_size(sccomm, &size));
  PetscCall(PetscMalloc1(2 * size, &all));
  PetscCallMPI(MPI_Allgather(mine, 2, MPIU_INT, all, 2, MPIU_INT, sccomm));
  PetscCall(PetscMalloc1(size + 1, ranges));
  for (PetscMPIInt q = 0; q < size; q++) {
    PetscCheck(all[2 * q] == (q ? all[2 * q - 1] : 0) && all[2 * q] <= all[2 * q + 1], sccomm, PETSC_ERR_ARG_WRONGSTATE,
               "Scene %s: rank %d owns disks [%" PetscInt_FMT ", %" PetscInt_FMT "), not the continuation of the previous rank's range",
               scname, q, all[2 * q], all[2 * q + 1]);
    (*ranges)[q] = all[2 * q];
  }
  (*ranges)[size] = size ? all[2 * size - 1] : 0;
  PetscCheck((*ranges)[size] == D.ndisks, sccomm, PETSC_ERR_ARG_WRONGSTATE,
             "Scene %s: the ranks own %" PetscInt_FMT " disks, not %" PetscInt_FMT, scname, (*ranges)[size], D.ndisks);
  PetscCall(PetscFree(all));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* Measures                                                                                                   */

/* Work of a contact in a step, for each of its disks: the sweeps dominate a step (thousands per step), and there an
   active contact costs about 6 times an inactive one, whose zero impulse is skipped (docs/scaling.md, "Partition
   work"). Each disk counts 1 more for its own work outside the sweeps. */
#define KERGS_WORK_INACTIVE 1
#define KERGS_WORK_ACTIVE 6
static inline PetscInt ContactWork(const KergsActivity *act, const KergsContact *c)
{
  return KergsContactIsActive(act, c) ? KERGS_WORK_ACTIVE : KERGS_WORK_INACTIVE;
}

/* Modelled work (per grain 1 + ContactWork of its contacts, summed over a rank's grains) and edge cut from each
   rank's own contacts; ghosts are those of the current ghost layer. A contact with a ghost b adds to the work of b's
   owner. With measured work, once every rank has timed its sweeps, a rank's work is that time, and its factor
   work_scale = (time / model) / (total time / total model) turns the model of its grains into time for METIS. */
PetscErrorCode KergsPartitionMeasure(KergsPartition p, KergsScene sc, KergsContacts ct, KergsPartitionMeasures *m)
{
  PetscInt      nct;
  KergsContact *cts;
  KergsDisks    D;
  const char   *scname;
  PetscMPIInt   rank, size;
  PetscInt     *buf;

  KergsActivity act;

  PetscFunctionBeginUser;
  PetscCall(KergsContactsGetLocal(ct, &nct, &cts));
  PetscCall(KergsContactsGetActivity(ct, sc, &act));
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetName(sc, &scname));
  PetscCallMPI(MPI_Comm_rank(p->comm, &rank));
  PetscCallMPI(MPI_Comm_size(p->comm, &size));
  /* buf: work per rank [0, size), edges, cut, ghosts */
  PetscCall(PetscCalloc1(size + 3, &buf));
  buf[rank] += D.nowned;
  for (PetscInt k = 0; k < nct; k++) {
    const KergsContact *c = &cts[k];
    const PetscInt      w = ContactWork(&act, c);

    buf[rank] += w;
    if (c->kind != KERGS_CONTACT_DISK_DISK) continue;
    PetscCheck(c->b >= 0 && c->b < D.nlocal, PETSC_COMM_SELF, PETSC_ERR_ARG_WRONGSTATE,
               "Scene %s: contact %" PetscInt_FMT " names local disk %" PetscInt_FMT " of %" PetscInt_FMT
               " (contacts older than the ghost layer)",
               scname, k, c->b, D.nlocal);
    buf[size]++;
    if (c->b < D.nowned)
      buf[rank] += w;
    else {
      buf[D.ghost_owner[c->b - D.nowned]] += w;
      buf[size + 1]++;
    }
  }
  buf[size + 2] = D.nlocal - D.nowned;
  PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, buf, size + 3, MPIU_INT, MPI_SUM, p->comm));
  m->edges       = buf[size];
  m->edgecut     = buf[size + 1];
  m->ghosts      = buf[size + 2];
  m->my_grains   = D.nowned;
  m->my_contacts = nct;
  m->my_ghosts   = D.nlocal - D.nowned;
  m->my_work     = (PetscReal)buf[rank];
  m->work_max    = 0;
  m->work_mean   = 0;
  for (PetscMPIInt q = 0; q < size; q++) {
    m->work_max = PetscMax(m->work_max, (PetscReal)buf[q]);
    m->work_mean += (PetscReal)buf[q];
  }
  m->work_mean /= size;
  m->my_seconds       = p->state.compute_seconds;
  p->state.work_scale = 1.0;
  if (p->work == KERGS_PARTITION_WORK_MEASURED) {
    const PetscReal model = m->work_mean * size;                                                             /* total modelled work */
    PetscReal       t[3]  = {p->state.compute_seconds, p->state.compute_seconds, -p->state.compute_seconds}; /* sum; max, -min */

    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &t[0], 1, MPIU_REAL, MPI_SUM, p->comm));
    PetscCallMPI(MPI_Allreduce(MPI_IN_PLACE, &t[1], 2, MPIU_REAL, MPI_MAX, p->comm));
    if (-t[2] > 0 && model > 0) { /* every rank timed some sweeps */
      m->work_max         = t[1];
      m->work_mean        = t[0] / size;
      p->state.work_scale = m->my_work > 0 ? (p->state.compute_seconds / m->my_work) / (t[0] / model) : 1.0;
    }
  }
  m->imbalance = m->work_mean > 0 ? m->work_max / m->work_mean : 1.0;
  /* no partition beats max(1, size / ndisks): a rank holds at least one grain's work once ranks outnumber grains */
  m->imbalance_bound = D.ndisks > 0 ? PetscMax(1.0, (PetscReal)size / (PetscReal)D.ndisks) : 1.0;
  PetscCall(PetscFree(buf));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPartitionObserve(KergsPartition p, KergsScene sc, KergsContacts ct, PetscReal sweep_seconds, PetscReal compute_seconds,
                                     KergsPartitionMeasures *out)
{
  PetscInt                scstep;
  KergsPartitionMeasures *m = &p->last;
  PetscMPIInt             rank;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetStep(sc, &scstep, NULL, NULL));
  p->state.compute_seconds = compute_seconds;
  PetscCall(KergsPartitionMeasure(p, sc, ct, m));
  m->repartitions = p->state.nrepartitions;
  if (out) *out = *m;
  if (!p->viewer) PetscFunctionReturn(0);
  PetscCallMPI(MPI_Comm_rank(p->comm, &rank));
  PetscCall(PetscViewerASCIIPushSynchronized(p->viewer));
  PetscCall(PetscViewerASCIISynchronizedPrintf(
      p->viewer,
      "[partition] step %5" PetscInt_FMT " rank %3d: grains %6" PetscInt_FMT " ghosts %6" PetscInt_FMT " contacts %7" PetscInt_FMT
      " work %8.0f sweep %.3g s (arithmetic %.3g s)\n",
      scstep, rank, m->my_grains, m->my_ghosts, m->my_contacts, (double)m->my_work, (double)sweep_seconds, (double)compute_seconds));
  PetscCall(PetscViewerFlush(p->viewer));
  PetscCall(PetscViewerASCIIPopSynchronized(p->viewer));
  PetscCall(PetscViewerASCIIPrintf(p->viewer,
                                   "[partition] step %5" PetscInt_FMT ": %s, edge cut %" PetscInt_FMT " of %" PetscInt_FMT
                                   " contact edges, imbalance %.4f, ghosts %" PetscInt_FMT ", repartitions %" PetscInt_FMT "\n",
                                   scstep, KergsPartitionTypes[p->state.last_method], m->edgecut, m->edges, (double)m->imbalance, m->ghosts,
                                   p->state.nrepartitions));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* Renumbering (migration)                                                                                    */

/* order must be a permutation and counts a split of ndisks over the ranks, the same on every rank (checked
   here on the local copy; the caller guarantees equality across ranks, e.g. by a broadcast). */
static PetscErrorCode CheckRenumbering(KergsScene sc, const PetscInt order[], const PetscInt counts[], PetscMPIInt size, PetscInt *old2new)
{
  KergsDisks  D;
  const char *scname;
  MPI_Comm    sccomm;
  PetscInt    total = 0;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetName(sc, &scname));
  PetscCall(KergsSceneGetComm(sc, &sccomm));
  for (PetscMPIInt q = 0; q < size; q++) {
    PetscCheck(counts[q] >= 0, sccomm, PETSC_ERR_ARG_OUTOFRANGE, "Renumbering of scene %s: rank %d gets %" PetscInt_FMT " disks", scname, q,
               counts[q]);
    total += counts[q];
  }
  PetscCheck(total == D.ndisks, sccomm, PETSC_ERR_ARG_WRONG,
             "Renumbering of scene %s: the ranks get %" PetscInt_FMT " disks in all, not %" PetscInt_FMT, scname, total, D.ndisks);
  for (PetscInt i = 0; i < D.ndisks; i++) old2new[i] = -1;
  for (PetscInt k = 0; k < D.ndisks; k++) {
    PetscCheck(order[k] >= 0 && order[k] < D.ndisks && old2new[order[k]] < 0, sccomm, PETSC_ERR_ARG_WRONG,
               "Renumbering of scene %s: new disk %" PetscInt_FMT " takes old disk %" PetscInt_FMT ", out of range or taken twice", scname,
               k, order[k]);
    old2new[order[k]] = k;
  }
  PetscFunctionReturn(0);
}

/* The migration proper: owned disk i gets the global index newidx[i], rank p then owns counts[p] disks. The
   contacts follow their disk a (keys and impulses), then the disks move. */
static PetscErrorCode MigrateOwned(KergsScene sc, KergsContacts ct, const PetscInt newidx[], const PetscInt counts[], PetscInt *nmoved)
{
  KergsDisks  D;
  MPI_Comm    sccomm;
  PetscMPIInt rank, size;
  PetscInt   *newranges, moved = 0;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetComm(sc, &sccomm));
  PetscCallMPI(MPI_Comm_rank(sccomm, &rank));
  PetscCallMPI(MPI_Comm_size(sccomm, &size));
  PetscCall(PetscMalloc1(size + 1, &newranges));
  newranges[0] = 0;
  for (PetscMPIInt q = 0; q < size; q++) newranges[q + 1] = newranges[q] + counts[q];
  for (PetscInt i = 0; i < D.nowned; i++) moved += KergsRangeOwner(newranges, size, newidx[i]) != rank;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &moved, 1, MPIU_INT, MPI_SUM, sccomm));
  if (ct) PetscCall(KergsContactsMigrate(ct, newidx, newranges)); /* reads the owned disks before they move */
  PetscCall(KergsSceneMigrate(sc, newidx, counts));
  if (nmoved) *nmoved = moved;
  PetscCall(PetscFree(newranges));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPartitionRenumber(KergsScene sc, KergsContacts ct, const PetscInt order[], const PetscInt counts[], PetscInt *nmoved)
{
  KergsDisks  D;
  MPI_Comm    sccomm;
  PetscMPIInt size;
  PetscInt   *old2new, *newidx;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetComm(sc, &sccomm));
  PetscCallMPI(MPI_Comm_size(sccomm, &size));
  PetscCall(PetscMalloc2(D.ndisks + 1, &old2new, D.nowned + 1, &newidx));
  PetscCall(CheckRenumbering(sc, order, counts, size, old2new));
  for (PetscInt i = 0; i < D.nowned; i++) newidx[i] = old2new[D.dstart + i];
  PetscCall(MigrateOwned(sc, ct, newidx, counts, nmoved));
  PetscCall(PetscFree2(old2new, newidx));
  PetscFunctionReturn(0);
}

/* ---------------------------------------------------------------------------------------------------------- */
/* Computing a partition (rank 0)                                                                             */

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
                          ? PetscMax(1, (PetscInt)(10.0 * p->state.work_scale * ContactWork(&act, &cts[k]) + 0.5))
                          : ContactWork(&act, &cts[k]);
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

/* What rank 0 computes and broadcasts besides the order (an array of PetscInt, broadcast as such). */
typedef struct {
  PetscInt  method;      /* the method used (a KergsPartitionType) */
  PetscInt  edgecut;     /* cut of the new partition on the graph it was computed from (-1: graph without edges) */
  PetscInt  status;      /* METIS status (METIS_OK = 1) */
  PetscInt  metis_tried; /* METIS ran (its result may have been replaced by the geometric one) */
  PetscReal imbalance;   /* imbalance of the new partition with the graph's work */
} PartitionOutcome;
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
                                  PetscInt part[], const PetscInt seq[], PetscInt order[], PetscInt counts[], PartitionOutcome *out)
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
                                             PetscInt order[], PetscInt counts[], PartitionOutcome *out)
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
    PetscInt        *order2, *counts2;
    PartitionOutcome alt;
    PetscBool        emptymetis = PETSC_FALSE, emptyalt = PETSC_FALSE;

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

/* From the new order computed on rank 0 (new index k holds old disk order[k]), each rank receives the new global
   index of each of its owned disks (*newidx, PetscFree): O(owned disks) per rank, not the whole order. */
static PetscErrorCode ScatterNewIndices(KergsScene sc, const PetscInt oldranges[], const PetscInt order[], PetscInt **newidx)
{
  KergsDisks  D;
  MPI_Comm    sccomm;
  PetscMPIInt rank, size, *counts = NULL, *displs = NULL;
  PetscInt   *old2new = NULL;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetComm(sc, &sccomm));
  PetscCallMPI(MPI_Comm_rank(sccomm, &rank));
  PetscCallMPI(MPI_Comm_size(sccomm, &size));
  if (rank == 0) {
    PetscCall(PetscMalloc3(D.ndisks + 1, &old2new, size, &counts, size, &displs));
    for (PetscInt k = 0; k < D.ndisks; k++) old2new[order[k]] = k;
    for (PetscMPIInt q = 0; q < size; q++) {
      counts[q] = (PetscMPIInt)(oldranges[q + 1] - oldranges[q]);
      displs[q] = (PetscMPIInt)oldranges[q];
    }
  }
  PetscCall(PetscMalloc1(D.nowned + 1, newidx));
  PetscCallMPI(MPI_Scatterv(old2new, counts, displs, MPIU_INT, *newidx, (PetscMPIInt)D.nowned, MPIU_INT, 0, sccomm));
  if (rank == 0) PetscCall(PetscFree3(old2new, counts, displs));
  PetscFunctionReturn(0);
}

/* Compute a partition with the object's type from the current contacts and renumber (collective). */
static PetscErrorCode Repartition(KergsPartition p, KergsScene sc, KergsContacts ct)
{
  KergsDisks       D;
  const char      *scname;
  PetscInt         scstep;
  PetscMPIInt      rank, size;
  PetscInt        *order, *counts, *oldranges, *newidx, moved;
  GrainGraph       g;
  PartitionOutcome out = {KERGS_PARTITION_CONTIGUOUS, -1, METIS_OK, PETSC_FALSE, 1.0};
  PetscLogDouble   t0, t1;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetName(sc, &scname));
  PetscCall(KergsSceneGetStep(sc, &scstep, NULL, NULL));
  PetscCall(PetscTime(&t0));
  PetscCall(PetscLogEventBegin(KERGS_Partition, 0, 0, 0, 0));
  PetscCallMPI(MPI_Comm_rank(p->comm, &rank));
  PetscCallMPI(MPI_Comm_size(p->comm, &size));
  PetscCall(GetRanges(sc, &oldranges));
  PetscCall(PetscMalloc2(rank == 0 ? D.ndisks + 1 : 1, &order, 2 * size, &counts));
  PetscCall(GatherGrainGraph(p, sc, ct, &g));
  if (rank == 0) PetscCall(ComputePartitionOnRoot(p, &g, oldranges, size, order, counts, &out));
  PetscCall(GrainGraphDestroy(&g));
  {
    PetscInt v[KERGS_OUTCOME_LEN] = {out.method, out.edgecut, out.status, out.metis_tried};
    PetscCallMPI(MPI_Bcast(v, KERGS_OUTCOME_LEN, MPIU_INT, 0, p->comm));
    out.method      = v[0];
    out.edgecut     = v[1];
    out.status      = v[2];
    out.metis_tried = v[3];
  }
  PetscCallMPI(MPI_Bcast(&out.imbalance, 1, MPIU_REAL, 0, p->comm));
  PetscCheck(out.status == METIS_OK, p->comm, PETSC_ERR_LIB,
             "METIS_PartGraphKway failed (status %" PetscInt_FMT ") partitioning the %" PetscInt_FMT " grains of scene %s into %d parts",
             out.status, D.ndisks, scname, size);
  PetscCallMPI(MPI_Bcast(counts, size, MPIU_INT, 0, p->comm));
  PetscCall(ScatterNewIndices(sc, oldranges, order, &newidx));
  PetscCall(MigrateOwned(sc, ct, newidx, counts, &moved));
  PetscCall(PetscFree(newidx));
  p->state.last_method    = out.method;
  p->state.provisional    = (PetscBool)(p->type == KERGS_PARTITION_METIS && !out.metis_tried);
  p->state.edgecut_base   = out.edgecut;
  p->state.imbalance_base = out.imbalance;
  p->state.nmoved += moved;
  PetscCall(PetscFree2(order, counts));
  PetscCall(PetscFree(oldranges));
  PetscCall(PetscLogEventEnd(KERGS_Partition, 0, 0, 0, 0));
  PetscCall(PetscTime(&t1));
  p->seconds += t1 - t0;
  PetscCall(PetscInfo(NULL,
                      "Scene %s step %" PetscInt_FMT ": %s partition, edge cut %" PetscInt_FMT ", imbalance %g, %" PetscInt_FMT
                      " grains moved, %.3g s\n",
                      scname, scstep, KergsPartitionTypes[out.method], out.edgecut, (double)out.imbalance, moved, (double)(t1 - t0)));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPartitionApply(KergsPartition p, KergsScene sc, KergsContacts ct)
{
  PetscMPIInt size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(p->comm, &size));
  if (size == 1) PetscFunctionReturn(0);
  PetscCall(Repartition(p, sc, ct));
  PetscFunctionReturn(0);
}

PetscErrorCode KergsPartitionUpdate(KergsPartition p, KergsScene sc, KergsContacts ct, PetscBool *repartitioned)
{
  KergsDisks             D;
  const char            *scname;
  PetscInt               scstep;
  KergsPartitionMeasures m;
  PetscMPIInt            size;
  PetscBool              dense, due, unbalanced;

  PetscFunctionBeginUser;
  PetscCall(KergsSceneGetDisks(sc, &D));
  PetscCall(KergsSceneGetName(sc, &scname));
  PetscCall(KergsSceneGetStep(sc, &scstep, NULL, NULL));
  if (repartitioned) *repartitioned = PETSC_FALSE;
  PetscCallMPI(MPI_Comm_size(p->comm, &size));
  if (size == 1 || p->type == KERGS_PARTITION_CONTIGUOUS) {
    p->state.initialized = PETSC_TRUE;
    PetscFunctionReturn(0);
  }
  if (!p->state.initialized) { /* before the first detection: geometric (metis falls back to it without contacts) */
    PetscCall(Repartition(p, sc, ct));
    p->state.initialized = PETSC_TRUE;
    if (repartitioned) *repartitioned = PETSC_TRUE;
    PetscFunctionReturn(0);
  }
  if (p->check_every == 0 || scstep % p->check_every != 0) PetscFunctionReturn(0);
  PetscCall(KergsPartitionMeasure(p, sc, ct, &m));
  if (p->state.edgecut_base < 0) p->state.edgecut_base = m.edgecut; /* the last partition saw no edges: its first measured cut */
  dense = (PetscBool)(2.0 * m.edges >= KERGS_PARTITION_MIN_DEGREE * D.ndisks && m.edges > 0 && D.ndisks >= size);
  /* an imbalance past the tolerance that is no worse than right after the last partition is what the partitioner
     could do (a few grains of uneven work): repartitioning again would change nothing, unless forced by tol = 1 */
  unbalanced = (PetscBool)(m.imbalance >= p->imbalance_tol * m.imbalance_bound &&
                           (p->imbalance_tol <= 1.0 || m.imbalance > p->state.imbalance_base));
  due        = (PetscBool)((p->state.provisional && dense) || unbalanced ||
                    (PetscReal)m.edgecut > p->edgecut_growth * (PetscReal)PetscMax(p->state.edgecut_base, 1));
  if (!due) PetscFunctionReturn(0);
  PetscCall(PetscInfo(NULL,
                      "Scene %s step %" PetscInt_FMT ": repartition (imbalance %g, bound %g; edge cut %" PetscInt_FMT
                      ", after the last partition %" PetscInt_FMT "%s)\n",
                      scname, scstep, (double)m.imbalance, (double)m.imbalance_bound, m.edgecut, p->state.edgecut_base,
                      p->state.provisional ? "; provisional" : ""));
  PetscCall(Repartition(p, sc, ct));
  p->state.nrepartitions++;
  if (repartitioned) *repartitioned = PETSC_TRUE;
  PetscFunctionReturn(0);
}
