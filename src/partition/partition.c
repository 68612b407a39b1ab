/* kergs partition: ownership of the grains by the ranks (docs/design.md: parallel layout), the policy and the migration.

   Rank p owns the disks of global indices [dstart, dend), so a partition is a new numbering of the disks, part
   after part. This file decides when to repartition (imbalance and edge cut measured every -partition_check_every
   steps); the new numbering is computed on rank 0 from the grain graph gathered there (src/partition/graph.c); each
   rank receives the new global index of its own disks (MPI_Scatterv); the disks then migrate to their new owners
   with their whole state (KergsSceneMigrate), and the contacts follow their disk a with their impulses, so that the
   next detection warm-starts them (Algorithm 1). */
#include <kergs/private/partitionimpl.h>

const char *const KergsPartitionTypes[] = {"contiguous", "geometric", "metis", "KergsPartitionType", "KERGS_PARTITION_", NULL};
const char *const KergsPartitionWorks[] = {"model", "measured", "KergsPartitionWork", "KERGS_PARTITION_WORK_", NULL};

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
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-partition_check_every",
                            "Steps between two checks of the partition (0: never repartition)", "", p->check_every, &p->check_every, NULL));
  PetscCall(PetscViewerDestroy(&p->viewer));
  PetscCall(PetscOptionsViewer(
      "-partition_view", "Print per step and rank: grains, ghosts, contacts, work, sweep time; and the edge cut (PETSc viewer syntax)",
      "KergsPartitionView", &p->viewer, &p->view_format, NULL));
  PetscCall(KergsOptionsBool(
      PetscOptionsObject, "-partition_metis_curve",
      "Join consecutive grains along a Hilbert curve by light edges in METIS's graph (locality for grains without contacts)", "",
      p->metis_curve, &p->metis_curve, NULL));
  PetscCall(PetscOptionsEnum(
      "-partition_work",
      "Work of a rank: measured (its time in the sweeps' arithmetic at the last step, spread over its grains by the model; balances what "
      "the model misses, not reproducible to the bit across runs) or model (active contacts count 6, inactive 1; deterministic)",
      "", KergsPartitionWorks, (PetscEnum)p->work, (PetscEnum *)&p->work, NULL));
  PetscCall(KergsOptionsInt(PetscOptionsObject, "-partition_metis_seed", "Seed of METIS's random choices (fixed: reproducible partitions)",
                            "", p->metis_seed, &p->metis_seed, NULL));
  PetscOptionsEnd();
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
    const PetscInt      w = KergsPartitionContactWork(&act, c);

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
/* Repartitioning                                                                                             */

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
  KergsDisks            D;
  const char           *scname;
  PetscInt              scstep;
  PetscMPIInt           rank, size;
  PetscInt             *order, *counts, *oldranges, *newidx, moved;
  KergsPartitionOutcome out;
  PetscLogDouble        t0, t1;

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
  PetscCall(KergsPartitionComputeOrder(p, sc, ct, oldranges, order, counts, &out));
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
