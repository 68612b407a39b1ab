/* Partition and migration of the distributed engine: the physics does not depend on the number of ranks nor on
   how the grains are numbered and owned. Each check compares a run on PETSC_COMM_WORLD against a reference run of
   the same scene in the same process (on PETSC_COMM_SELF, or on PETSC_COMM_WORLD with the contiguous layout), grain
   by grain through the persistent ids, after every step. Runs on 1, 2 and 3 ranks. */
static const char help[] = "kergs partition tests: same physics on 1 and n ranks, renumbering, warm start across swaps, robustness.\n";

#include "testing.h"
#include "internals.h"

/* Frictionless, with a tight natural-map criterion: the velocities are unique, so runs must agree closely. */
#define TIGHT "-friction 0 -solver_criterion natural -solver_tol 1e-10 -solver_max_it 10000 "
#define CONFINE5 "-options_file cases/confine5.opts " TIGHT
/* ~200 disks dropped from a grid into a box: the contact graph grows from nothing to a packing. */
#define DEPOSIT                                                                                                                            \
  "-gravity 0,-9.81 -dt 4e-3 -disks_source random -random_n 200 -random_box 0,0,0.4,1.0 -random_radius 0.01,0.02 -random_seed 7 "          \
  "-box 0,0,0.4,1.2 -box_open_top " TIGHT
#define FORCE_REPARTITION "-partition_check_every 1 -partition_imbalance_tol 1.0 "

/* MakeStepperOn (testing.h) with the options of opts followed by extra (may be NULL). */
static PetscErrorCode StepperWithExtra(MPI_Comm comm, const char *opts, const char *extra, KergsStepper *st)
{
  char all[4096];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(all, sizeof(all), "%s %s", opts, extra ? extra : ""));
  PetscCall(MakeStepperOn(comm, all, st));
  PetscFunctionReturn(0);
}

/* The state of every grain by id, gathered on every rank: x, v (KERGS_DIM each), omega, radius. Fails (ok false)
   unless the ids are a permutation of 0 .. ndisks-1. */
typedef struct {
  PetscInt   n;
  PetscReal *x, *v, *omega, *radius;
} GrainsById;

static PetscErrorCode GatherGrainsById(KergsScene sc, GrainsById *g, PetscBool *ok)
{
  PetscInt *ids, *seen;

  PetscFunctionBeginUser;
  g->n = sc->ndisks;
  PetscCall(PetscMalloc4(KERGS_DIM * g->n + 1, &g->x, KERGS_DIM * g->n + 1, &g->v, g->n + 1, &g->omega, g->n + 1, &g->radius));
  PetscCall(PetscMalloc1(g->n + 1, &ids));
  PetscCall(PetscCalloc1(g->n + 1, &seen));
  PetscCall(KergsSceneAllGatherInt(sc, sc->id, 1, ids));
  *ok = PETSC_TRUE;
  for (PetscInt i = 0; i < g->n; i++) {
    if (ids[i] < 0 || ids[i] >= g->n || seen[ids[i]])
      *ok = PETSC_FALSE;
    else
      seen[ids[i]] = 1;
  }
  if (*ok) {
    PetscCall(GatherById(sc, sc->x, KERGS_DIM, g->x));
    PetscCall(GatherById(sc, sc->v, KERGS_DIM, g->v));
    PetscCall(GatherById(sc, sc->omega, KERGS_NROT, g->omega));
    PetscCall(GatherById(sc, sc->radius, 1, g->radius));
  }
  PetscCall(PetscFree(seen));
  PetscCall(PetscFree(ids));
  PetscFunctionReturn(0);
}

static PetscErrorCode GrainsByIdDestroy(GrainsById *g)
{
  PetscFunctionBeginUser;
  PetscCall(PetscFree4(g->x, g->v, g->omega, g->radius));
  PetscFunctionReturn(0);
}

/* Largest difference of velocities (relative to the largest speed) and positions (relative to the smallest
   radius) between two scenes of the same grains, matched by id (collective on each scene's communicator). */
static PetscErrorCode CompareById(KergsScene s, KergsScene t, PetscReal *dv, PetscReal *dx)
{
  GrainsById gs, gt;
  PetscReal  vmax = 0, rmin = PETSC_MAX_REAL;
  PetscBool  oks, okt;

  PetscFunctionBeginUser;
  *dv = *dx = PETSC_MAX_REAL;
  PetscCall(GatherGrainsById(s, &gs, &oks));
  PetscCall(GatherGrainsById(t, &gt, &okt));
  if (oks && okt && gs.n == gt.n) {
    *dv = *dx = 0;
    for (PetscInt i = 0; i < gs.n; i++) {
      rmin = PetscMin(rmin, gs.radius[i]);
      for (PetscInt d = 0; d < KERGS_DIM; d++) vmax = PetscMax(vmax, PetscAbsReal(gs.v[KERGS_DIM * i + d]));
    }
    for (PetscInt i = 0; i < gs.n; i++) {
      for (PetscInt d = 0; d < KERGS_DIM; d++) {
        *dv = PetscMax(*dv, PetscAbsReal(gs.v[KERGS_DIM * i + d] - gt.v[KERGS_DIM * i + d]));
        *dx = PetscMax(*dx, PetscAbsReal(gs.x[KERGS_DIM * i + d] - gt.x[KERGS_DIM * i + d]));
      }
      *dv = PetscMax(*dv, PetscAbsReal(gs.omega[i] - gt.omega[i]) * gs.radius[i]);
    }
    *dv /= PetscMax(vmax, PETSC_SMALL);
    *dx /= rmin;
  }
  PetscCall(GrainsByIdDestroy(&gs));
  PetscCall(GrainsByIdDestroy(&gt));
  PetscFunctionReturn(0);
}

/* A contact keyed by grain ids: (lower id, higher id, 0) for a disk-disk pair, (id, wall, 1) for a wall. */
typedef struct {
  PetscInt  k[3];
  PetscReal r[KERGS_MAXCOMP];
} IdContact;

static int CompareIdContacts(const void *x, const void *y)
{
  const IdContact *p = (const IdContact *)x, *q = (const IdContact *)y;
  for (int i = 0; i < 3; i++)
    if (p->k[i] != q->k[i]) return p->k[i] < q->k[i] ? -1 : 1;
  return 0;
}

/* Every rank's contacts keyed by ids, gathered on every rank and sorted. */
static PetscErrorCode GatherIdContacts(KergsStepper st, PetscInt *n, IdContact **all)
{
  KergsScene    sc = st->scene;
  KergsContacts ct = st->contacts;
  IdContact    *mine;
  PetscMPIInt   size, nmine, *counts, *displs;
  MPI_Datatype  type;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(st->comm, &size));
  PetscCall(PetscMalloc1(ct->n + 1, &mine));
  for (PetscInt k = 0; k < ct->n; k++) {
    const KergsContact *c  = &ct->c[k];
    PetscInt            ia = sc->id[c->a];
    if (c->kind == KERGS_CONTACT_DISK_DISK) {
      PetscInt ib  = c->idb; /* also right for a migrated list, which keeps no local b */
      mine[k].k[0] = PetscMin(ia, ib);
      mine[k].k[1] = PetscMax(ia, ib);
      mine[k].k[2] = 0;
    } else {
      mine[k].k[0] = ia;
      mine[k].k[1] = c->idb; /* the wall */
      mine[k].k[2] = 1;
    }
    for (PetscInt d = 0; d < KERGS_MAXCOMP; d++) mine[k].r[d] = c->r[d];
  }
  nmine = (PetscMPIInt)ct->n;
  PetscCall(PetscMalloc2(size, &counts, size + 1, &displs));
  PetscCallMPI(MPI_Allgather(&nmine, 1, MPI_INT, counts, 1, MPI_INT, st->comm));
  displs[0] = 0;
  for (PetscMPIInt q = 0; q < size; q++) displs[q + 1] = displs[q] + counts[q];
  *n = displs[size];
  PetscCall(PetscMalloc1(*n + 1, all));
  PetscCallMPI(MPI_Type_contiguous((PetscMPIInt)sizeof(IdContact), MPI_BYTE, &type));
  PetscCallMPI(MPI_Type_commit(&type));
  PetscCallMPI(MPI_Allgatherv(mine, nmine, type, *all, counts, displs, type, st->comm));
  PetscCallMPI(MPI_Type_free(&type));
  qsort(*all, (size_t)*n, sizeof(IdContact), CompareIdContacts);
  PetscCall(PetscFree2(counts, displs));
  PetscCall(PetscFree(mine));
  PetscFunctionReturn(0);
}

/* Invariants of a run's layout, global (the same answer on every rank): the owned ranges tile [0, ndisks) in rank
   order, the ids are a permutation, the local arrays hold the owned disks in global-index order then ghosts owned
   elsewhere, every ghost has its owner's state, every contact has an owned disk a and a local disk b of larger id,
   and the lists are sorted by (a, kind, idb). */
static PetscErrorCode LayoutIsValid(KergsStepper st, PetscBool *valid)
{
  KergsScene    sc = st->scene;
  KergsContacts ct = st->contacts;
  PetscMPIInt   size;
  PetscInt     *ranges, bad = 0, mine[2] = {sc->dstart, sc->dend};
  GrainsById    g;
  PetscBool     ok;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(st->comm, &size));
  PetscCall(PetscMalloc1(2 * size, &ranges));
  PetscCallMPI(MPI_Allgather(mine, 2, MPIU_INT, ranges, 2, MPIU_INT, st->comm));
  for (PetscMPIInt q = 0; q < size; q++) bad += ranges[2 * q] != (q ? ranges[2 * q - 1] : 0) || ranges[2 * q + 1] < ranges[2 * q];
  bad += ranges[2 * size - 1] != sc->ndisks;
  bad += sc->nowned != sc->dend - sc->dstart || sc->nlocal < sc->nowned;
  PetscCall(GatherGrainsById(sc, &g, &ok));
  bad += !ok;
  for (PetscInt i = 0; ok && i < sc->nlocal; i++) {
    bad += i < sc->nowned ? sc->gidx[i] != sc->dstart + i : (sc->gidx[i] >= sc->dstart && sc->gidx[i] < sc->dend);
    for (PetscInt d = 0; d < KERGS_DIM; d++) /* a ghost is an exact copy */
      bad += sc->x[KERGS_DIM * i + d] != g.x[KERGS_DIM * sc->id[i] + d] || sc->v[KERGS_DIM * i + d] != g.v[KERGS_DIM * sc->id[i] + d];
  }
  for (PetscInt k = 0; k < ct->n; k++) {
    const KergsContact *c = &ct->c[k];
    bad += c->a < 0 || c->a >= sc->nowned;
    if (c->kind == KERGS_CONTACT_DISK_DISK) bad += c->b < 0 || c->b >= sc->nlocal || sc->id[c->b] <= sc->id[c->a] || c->idb != sc->id[c->b];
    if (k > 0) {
      const KergsContact *p = &ct->c[k - 1];
      bad += p->a > c->a || (p->a == c->a && (p->kind > c->kind || (p->kind == c->kind && p->idb >= c->idb)));
    }
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &bad, 1, MPIU_INT, MPI_SUM, st->comm));
  *valid = (PetscBool)(bad == 0);
  PetscCall(GrainsByIdDestroy(&g));
  PetscCall(PetscFree(ranges));
  PetscFunctionReturn(0);
}

/* The same contact pairs (by ids) in both runs, each exactly once. */
static PetscErrorCode SameContactSet(KergsStepper s, KergsStepper t, PetscBool *same)
{
  IdContact *a, *b;
  PetscInt   na, nb;

  PetscFunctionBeginUser;
  PetscCall(GatherIdContacts(s, &na, &a));
  PetscCall(GatherIdContacts(t, &nb, &b));
  *same = (PetscBool)(na == nb && s->contacts->nglobal == na && t->contacts->nglobal == nb);
  for (PetscInt k = 0; *same && k < na; k++)
    *same = (PetscBool)(CompareIdContacts(&a[k], &b[k]) == 0 && (k == 0 || CompareIdContacts(&a[k - 1], &a[k]) < 0));
  PetscCall(PetscFree(a));
  PetscCall(PetscFree(b));
  PetscFunctionReturn(0);
}

typedef struct {
  PetscInt  compared, contact_mismatch, layout_bad, convergence_mismatch, first_unconverged;
  PetscReal dv, dx;
} Lockstep;

/* Step a reference and a test run side by side and compare them after every step, as long as the reference's
   solves converge (a solve stopped by the sweep cap depends on the sweep order, so the runs may part there). */
static PetscErrorCode RunLockstep(KergsStepper ref, KergsStepper tst, PetscInt nsteps, Lockstep *L)
{
  PetscFunctionBeginUser;
  PetscCall(PetscMemzero(L, sizeof(*L)));
  L->first_unconverged = -1;
  for (PetscInt s = 0; s < nsteps; s++) {
    PetscInt  nr = ref->nonconverged, nt = tst->nonconverged;
    PetscBool valid, same                = PETSC_FALSE;
    PetscReal dv, dx;

    PetscCall(KergsStepperStep(ref));
    PetscCall(KergsStepperStep(tst));
    PetscCall(LayoutIsValid(tst, &valid));
    L->layout_bad += !valid;
    PetscCall(SameContactSet(ref, tst, &same));
    if (L->first_unconverged >= 0) continue;
    if (ref->nonconverged > nr) {
      L->first_unconverged = s + 1;
      continue;
    }
    L->convergence_mismatch += tst->nonconverged > nt;
    L->contact_mismatch += !same;
    PetscCall(CompareById(ref->scene, tst->scene, &dv, &dx));
    L->dv = PetscMax(L->dv, dv);
    L->dx = PetscMax(L->dx, dx);
    L->compared++;
  }
  PetscFunctionReturn(0);
}

static PetscErrorCode ReportLockstep(const char *label, const Lockstep *L, PetscInt min_compared)
{
  char what[256];

  PetscFunctionBeginUser;
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: steps compared (reference converged)", label));
  PetscCall(Check((PetscBool)(L->compared >= min_compared), what, (PetscReal)L->compared, (PetscReal)min_compared));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: velocities by id, relative to the largest speed", label));
  PetscCall(Check((PetscBool)(L->dv < 1e-6), what, L->dv, 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: positions by id, relative to the smallest radius", label));
  PetscCall(Check((PetscBool)(L->dx < 1e-6), what, L->dx, 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: steps whose contact set (by ids) differs", label));
  PetscCall(Check((PetscBool)(L->contact_mismatch == 0), what, (PetscReal)L->contact_mismatch, 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: steps converged in the reference but not in the test", label));
  PetscCall(Check((PetscBool)(L->convergence_mismatch == 0), what, (PetscReal)L->convergence_mismatch, 0));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: steps with a broken layout (ranges, ids, replicas, ownership)", label));
  PetscCall(Check((PetscBool)(L->layout_bad == 0), what, (PetscReal)L->layout_bad, 0));
  PetscFunctionReturn(0);
}

static PetscErrorCode ReportPartition(const char *label, KergsStepper st)
{
  KergsPartition p = st->partition;

  PetscFunctionBeginUser;
  PetscCall(PetscPrintf(
      PETSC_COMM_WORLD,
      "     %s: partition %s (latest %s), %" PetscInt_FMT " repartitions, %" PetscInt_FMT " grains moved; edge cut %" PetscInt_FMT
      " of %" PetscInt_FMT " edges, imbalance %.4f, ghosts %" PetscInt_FMT ", ghost layers built %" PetscInt_FMT "\n",
      label, KergsPartitionTypes[p->type], KergsPartitionTypes[p->state.last_method], p->state.nrepartitions, p->state.nmoved,
      p->last.edgecut, p->last.edges, (double)p->last.imbalance, p->last.ghosts, st->scene->ghost_rebuilds));
  PetscFunctionReturn(0);
}

/* Same physics on 1 rank (PETSC_COMM_SELF, in this process) and on every rank (default partition: metis). */
static PetscErrorCode TestSamePhysics(const char *label, const char *opts, PetscInt nsteps, PetscInt min_compared)
{
  KergsStepper ref, tst;
  Lockstep     L;

  PetscFunctionBeginUser;
  PetscCall(StepperWithExtra(PETSC_COMM_SELF, opts, NULL, &ref));
  PetscCall(StepperWithExtra(PETSC_COMM_WORLD, opts, NULL, &tst));
  PetscCall(RunLockstep(ref, tst, nsteps, &L));
  PetscCall(ReportLockstep(label, &L, min_compared));
  PetscCall(ReportPartition(label, tst));
  PetscCall(KergsStepperDestroy(&ref));
  PetscCall(KergsStepperDestroy(&tst));
  PetscFunctionReturn(0);
}

/* The ghost layer follows moving grains: in the falling deposit (grains move far more than the skin), the layer is
   rebuilt on displacement, not only after repartitions, and the run still matches the 1-rank one step by step
   (TestSamePhysics above); with a skin as large as the box it is never rebuilt after the first build. */
static PetscErrorCode TestGhostRebuilds(void)
{
  KergsStepper st;
  PetscMPIInt  size;
  PetscInt     built[2];

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  for (PetscInt big = 0; big < 2; big++) {
    PetscCall(
        StepperWithExtra(PETSC_COMM_WORLD, DEPOSIT, big ? "-partition_type contiguous -ghost_skin 2" : "-partition_type contiguous", &st));
    for (PetscInt s = 0; s < 50; s++) PetscCall(KergsStepperStep(st));
    built[big] = st->scene->ghost_rebuilds;
    PetscCall(KergsStepperDestroy(&st));
  }
  if (size > 1) {
    PetscCall(Check((PetscBool)(built[0] > 1), "ghosts: rebuilt as the grains fall (default skin)", (PetscReal)built[0], 2));
    PetscCall(Check((PetscBool)(built[1] == 1), "ghosts: built once with a skin larger than the box", (PetscReal)built[1], 1));
  } else
    PetscCall(Check((PetscBool)(built[0] == 0 && built[1] == 0), "ghosts: none on one rank", (PetscReal)(built[0] + built[1]), 0));
  PetscFunctionReturn(0);
}

/* Renumbering keeps physics: METIS repartitioning at every step against the contiguous layout, both on
   PETSC_COMM_WORLD, and against the 1-rank run for the contact set. */
static PetscErrorCode TestRenumberingKeepsPhysics(void)
{
  KergsStepper ref, tst;
  Lockstep     L;
  PetscMPIInt  size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(StepperWithExtra(PETSC_COMM_WORLD, DEPOSIT, "-partition_type contiguous", &ref));
  PetscCall(StepperWithExtra(PETSC_COMM_WORLD, DEPOSIT, "-partition_type metis " FORCE_REPARTITION, &tst));
  PetscCall(RunLockstep(ref, tst, 50, &L));
  PetscCall(ReportLockstep("deposit, metis every step vs contiguous", &L, 50));
  PetscCall(ReportPartition("deposit, metis every step", tst));
  if (size > 1) {
    PetscCall(Check((PetscBool)(tst->partition->state.nrepartitions == 49), "deposit: one repartition per step after the first",
                    (PetscReal)tst->partition->state.nrepartitions, 49));
    PetscCall(Check((PetscBool)(tst->partition->state.last_method == KERGS_PARTITION_METIS),
                    "deposit: METIS once the packing has formed (1 = metis)", tst->partition->state.last_method == KERGS_PARTITION_METIS,
                    1));
    /* the generator fills the box row by row: the contiguous split is a stack of layers, of small cut but
       unbalanced work once the lower layers are packed */
    PetscCall(Check((PetscBool)(tst->partition->last.imbalance <= 1.10), "deposit: METIS work imbalance within the default tolerance",
                    tst->partition->last.imbalance, 1.10));
    PetscCall(Check((PetscBool)(tst->partition->last.imbalance <= ref->partition->last.imbalance),
                    "deposit: METIS work imbalance <= contiguous", tst->partition->last.imbalance, ref->partition->last.imbalance));
    PetscCall(ReportPartition("deposit, contiguous", ref));
  }
  PetscCall(KergsStepperDestroy(&ref));
  PetscCall(KergsStepperDestroy(&tst));
  PetscFunctionReturn(0);
}

/* Per grain id, the force and torque the contacts put on it: r_n n + r_t t and -R_a r_t on
   body a, the opposite force and -R_b r_t on body b. */
static PetscErrorCode ImpulsesById(KergsStepper st, PetscReal *P)
{
  KergsScene sc = st->scene;

  PetscFunctionBeginUser;
  PetscCall(PetscArrayzero(P, 3 * sc->ndisks));
  for (PetscInt k = 0; k < st->contacts->n; k++) {
    const KergsContact *c  = &st->contacts->c[k];
    PetscInt            ia = sc->id[c->a];
    for (PetscInt d = 0; d < 2; d++) P[3 * ia + d] += c->r[0] * c->n[d] + c->r[1] * c->t[d];
    P[3 * ia + 2] += -c->ra * c->r[1];
    if (c->kind == KERGS_CONTACT_DISK_DISK) {
      PetscInt ib = c->idb;
      for (PetscInt d = 0; d < 2; d++) P[3 * ib + d] -= c->r[0] * c->n[d] + c->r[1] * c->t[d];
      P[3 * ib + 2] += -c->rb * c->r[1];
    }
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, P, 3 * sc->ndisks, MPIU_REAL, MPI_SUM, st->comm));
  PetscFunctionReturn(0);
}

static PetscReal MaxDiff(PetscInt n, const PetscReal *a, const PetscReal *b, PetscReal *scale)
{
  PetscReal d = 0;

  *scale = 0;
  for (PetscInt i = 0; i < n; i++) {
    d      = PetscMax(d, PetscAbsReal(a[i] - b[i]));
    *scale = PetscMax(*scale, PetscAbsReal(a[i]));
  }
  return d;
}

/* Migration keeps the impulses: reversing the numbering moves grains between ranks (on more than one rank) and
   renumbers every grain; the contacts travel with their disk a, keyed by grain ids, with their (r_n, r_t). A pair's
   frame is oriented by grain ids (a has the smaller id), so no frame ever flips: the next detection finds every pair
   persistent, carries every impulse over, and the contacts put the same force and torque on every grain as before.
   With friction, so that r_t != 0; then without, where the velocities are unique and the run must go on like an
   untouched one. (With friction the velocities need not be unique: a different sweep order across ranks may converge
   to another solution.) */
static PetscErrorCode TestMigrationKeepsImpulses(PetscBool frictional)
{
  const char *opts =
      frictional
          ? "-options_file cases/confine5.opts -solver_criterion natural -solver_tol 1e-12 -solver_max_it 20000 -partition_type contiguous"
          : "-options_file cases/confine5.opts -partition_type contiguous " TIGHT;
  const char  *label = frictional ? "migration, frictional" : "migration, frictionless";
  char         what[256];
  KergsStepper ref, tst;
  PetscInt     n, *order, *counts, nbefore, nafter, nmoved, ncarried = 0, npersist = 0, mismatched = 0;
  PetscMPIInt  size;
  IdContact   *before, *after;
  PetscReal   *P0, *P1, scale, rtmax = 0;
  Lockstep     L;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(StepperWithExtra(PETSC_COMM_SELF, opts, NULL, &ref));
  PetscCall(StepperWithExtra(PETSC_COMM_WORLD, opts, NULL, &tst));
  for (PetscInt s = 0; s < 2; s++) {
    PetscCall(KergsStepperStep(ref));
    PetscCall(KergsStepperStep(tst));
  }
  n = tst->scene->ndisks;
  PetscCall(PetscMalloc4(n, &order, size, &counts, 3 * n, &P0, 3 * n, &P1));
  /* frames at the current positions (the impulses carried over), to compare with those found after the migration */
  PetscCall(KergsContactsDetect(tst->contacts, tst->scene));
  PetscCall(GatherIdContacts(tst, &nbefore, &before));
  PetscCall(ImpulsesById(tst, P0));
  for (PetscInt k = 0; k < nbefore; k++) rtmax = PetscMax(rtmax, PetscAbsReal(before[k].r[1]));
  /* reverse the numbering; rank q takes as many grains as rank size-1-q had */
  for (PetscInt k = 0; k < n; k++) order[k] = n - 1 - k;
  {
    PetscInt mine = tst->scene->nowned;
    PetscCallMPI(MPI_Allgather(&mine, 1, MPIU_INT, counts, 1, MPIU_INT, PETSC_COMM_WORLD));
    for (PetscMPIInt q = 0; q < size / 2; q++) {
      PetscInt t           = counts[q];
      counts[q]            = counts[size - 1 - q];
      counts[size - 1 - q] = t;
    }
  }
  PetscCall(KergsPartitionRenumber(tst->scene, tst->contacts, order, counts, &nmoved));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: grains changed rank (none on one rank)", label));
  PetscCall(Check((PetscBool)(size > 1 ? nmoved > 0 : nmoved == 0), what, (PetscReal)nmoved, size > 1 ? 1 : 0));
  PetscCall(GatherIdContacts(tst, &nafter, &after));
  for (PetscInt k = 0; k < PetscMin(nbefore, nafter); k++)
    mismatched += CompareIdContacts(&before[k], &after[k]) != 0 || before[k].r[0] != after[k].r[0] || before[k].r[1] != after[k].r[1];
  mismatched += nbefore != nafter;
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: the contacts moved with the same pairs (by ids) and the same (r_n, r_t)", label));
  PetscCall(Check((PetscBool)(mismatched == 0), what, (PetscReal)mismatched, 0));
  /* the next detection carries every impulse over, by pair */
  PetscCall(KergsContactsDetect(tst->contacts, tst->scene));
  PetscCall(PetscFree(after));
  PetscCall(GatherIdContacts(tst, &nafter, &after));
  for (PetscInt k = 0; k < tst->contacts->n; k++) npersist += tst->contacts->c[k].persistent;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &npersist, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  for (PetscInt k = 0; k < PetscMin(nbefore, nafter); k++)
    ncarried += CompareIdContacts(&before[k], &after[k]) == 0 && before[k].r[0] == after[k].r[0] && before[k].r[1] == after[k].r[1];
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: detection finds every pair persistent", label));
  PetscCall(Check((PetscBool)(npersist == nbefore && nafter == nbefore), what, (PetscReal)npersist, (PetscReal)nbefore));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: detection carries every (r_n, r_t) over", label));
  PetscCall(Check((PetscBool)(ncarried == nbefore), what, (PetscReal)ncarried, (PetscReal)nbefore));
  PetscCall(ImpulsesById(tst, P1));
  PetscCall(PetscSNPrintf(what, sizeof(what), "%s: same force and torque on every grain, relative", label));
  PetscCall(Check((PetscBool)(MaxDiff(3 * n, P0, P1, &scale) <= 1e-14 * scale), what, MaxDiff(3 * n, P0, P1, &scale) / scale, 0));
  if (frictional)
    PetscCall(Check((PetscBool)(rtmax > 1e-8), "migration, frictional: some tangential impulse to carry (largest |r_t|)", rtmax, 1e-8));
  /* the next 2 steps (step 5 does not converge: the row starts to jam) */
  PetscCall(RunLockstep(ref, tst, 2, &L));
  if (frictional) {
    PetscCall(Check((PetscBool)(L.compared == 2 && L.convergence_mismatch == 0), "migration, frictional: the next 2 steps converge",
                    (PetscReal)(L.compared - L.convergence_mismatch), 2));
    PetscCall(Check((PetscBool)(L.contact_mismatch == 0 && L.layout_bad == 0),
                    "migration, frictional: same contacts as the 1-rank run, valid layout", (PetscReal)(L.contact_mismatch + L.layout_bad),
                    0));
    PetscCall(
        PetscPrintf(PETSC_COMM_WORLD,
                    "     migration, frictional: velocities by id differ from the 1-rank run by %.3g of the largest speed (not unique)\n",
                    (double)L.dv));
  } else
    PetscCall(ReportLockstep("migration, frictionless, after reversal", &L, 2));
  PetscCall(PetscFree(before));
  PetscCall(PetscFree(after));
  PetscCall(PetscFree4(order, counts, P0, P1));
  PetscCall(KergsStepperDestroy(&ref));
  PetscCall(KergsStepperDestroy(&tst));
  PetscFunctionReturn(0);
}

/* Robustness: more ranks than grains (a rank owns nothing), all grains on one rank, repartitioning every step. */
static PetscErrorCode TestRobustness(void)
{
  const char *two =
      "-gravity 0,-9.81 -dt 1e-3 -disks_source list -disks_x 0.5,0.5,1.5,0.52 -disks_radius 0.5 -box 0,0,2,2 -box_open_top " TIGHT;
  KergsStepper ref, tst;
  Lockstep     L;
  PetscMPIInt  size, rank;
  PetscInt     nowned, nempty;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  /* two grains on every rank, repartitioned (geometric: fewer grains than ranks or no edges) at every step */
  PetscCall(StepperWithExtra(PETSC_COMM_SELF, two, NULL, &ref));
  PetscCall(StepperWithExtra(PETSC_COMM_WORLD, two, "-partition_type metis -partition_view " FORCE_REPARTITION, &tst));
  PetscCall(RunLockstep(ref, tst, 5, &L));
  PetscCall(ReportLockstep("two grains, repartitioned every step", &L, 5));
  nowned = tst->scene->nowned;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &nowned, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  nempty = tst->scene->dend == tst->scene->dstart;
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &nempty, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  PetscCall(Check((PetscBool)(nowned == 2), "two grains: owned grains summed over ranks", (PetscReal)nowned, 2));
  PetscCall(
      Check((PetscBool)(nempty == PetscMax(size - 2, 0)), "two grains: ranks owning nothing", (PetscReal)nempty, PetscMax(size - 2, 0)));
  PetscCall(KergsStepperDestroy(&ref));
  PetscCall(KergsStepperDestroy(&tst));

  /* all grains on the first, then on the last rank (the one holding the free walls' DOFs, if any), mid-run */
  for (PetscInt where = 0; where < 2; where++) {
    PetscInt *order, *counts, n;
    char      label[64];

    PetscCall(StepperWithExtra(PETSC_COMM_SELF, DEPOSIT, NULL, &ref));
    PetscCall(StepperWithExtra(PETSC_COMM_WORLD, DEPOSIT, "-partition_type contiguous", &tst));
    PetscCall(RunLockstep(ref, tst, 5, &L));
    n = tst->scene->ndisks;
    PetscCall(PetscMalloc2(n, &order, size, &counts));
    for (PetscInt k = 0; k < n; k++) order[k] = k;
    for (PetscMPIInt q = 0; q < size; q++) counts[q] = 0;
    counts[where ? size - 1 : 0] = n;
    PetscCall(KergsPartitionRenumber(tst->scene, tst->contacts, order, counts, NULL));
    PetscCall(RunLockstep(ref, tst, 10, &L));
    PetscCall(PetscSNPrintf(label, sizeof(label), "deposit, all grains on rank %d", where ? size - 1 : 0));
    PetscCall(ReportLockstep(label, &L, 10));
    PetscCall(Check((PetscBool)(tst->scene->dend - tst->scene->dstart == (rank == (where ? size - 1 : 0) ? n : 0)),
                    "all on one rank: this rank's share", (PetscReal)(tst->scene->dend - tst->scene->dstart),
                    rank == (where ? size - 1 : 0) ? n : 0));
    PetscCall(PetscFree2(order, counts));
    PetscCall(KergsStepperDestroy(&ref));
    PetscCall(KergsStepperDestroy(&tst));
  }
  PetscFunctionReturn(0);
}

/* A grain touching grains of three ranks at once: disk 0 rests on disks 1 and 2 (on a frictionless floor, so that
   they slide apart and the stack collapses: every grain moves) and carries disk 3. With the contiguous split of 4 disks over 3 ranks (2, 1,
   1), disk 0 is on rank 0 with disk 1, disk 2 on rank 1 and disk 3 on rank 2: its three contacts join three ranks, and two of them need
   ghosts. The run must match the 1-rank run step by step, with every contact found once; on 3 ranks the check also asserts that the grain's
   neighbours are owned by 3 distinct ranks (on fewer ranks, by all of them). */
#define TRIPLE                                                                                                                             \
  "-gravity 0,-9.81 -dt 1e-3 -alert 0.01 -disks_source list -disks_radius 0.1 "                                                            \
  "-disks_x 0.5,0.273205081,0.4,0.100000001,0.6,0.100000001,0.5,0.473205082 "                                                              \
  "-walls floor -wall_floor_a 0,0 -wall_floor_b 1,0 -partition_type contiguous " TIGHT

static PetscErrorCode TestGrainOnThreeRanks(void)
{
  KergsStepper ref, tst;
  Lockstep     L;
  PetscMPIInt  size, rank;
  PetscInt     owners = 0, ncontacts0 = 0;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  PetscCall(StepperWithExtra(PETSC_COMM_SELF, TRIPLE, NULL, &ref));
  PetscCall(StepperWithExtra(PETSC_COMM_WORLD, TRIPLE, NULL, &tst));
  PetscCall(RunLockstep(ref, tst, 20, &L));
  PetscCall(ReportLockstep("grain on three ranks", &L, 20));
  {
    KergsScene sc      = tst->scene;
    PetscBool  seen[4] = {PETSC_FALSE, PETSC_FALSE, PETSC_FALSE, PETSC_FALSE};
    for (PetscInt k = 0; k < tst->contacts->n; k++) { /* disk 0 has the smallest id: it owns its disk-disk contacts */
      const KergsContact *c = &tst->contacts->c[k];
      if (c->kind != KERGS_CONTACT_DISK_DISK || sc->id[c->a] != 0) continue;
      ncontacts0++;
      seen[c->b < sc->nowned ? rank : sc->ghost_owner[c->b - sc->nowned]] = PETSC_TRUE;
    }
    for (PetscMPIInt q = 0; q < PetscMin(size, 4); q++) owners += seen[q];
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &owners, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &ncontacts0, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  PetscCall(Check((PetscBool)(ncontacts0 == 3), "grain on three ranks: grain 0 has 3 disk contacts", (PetscReal)ncontacts0, 3));
  PetscCall(Check((PetscBool)(owners == PetscMin(size, 3)), "grain on three ranks: its neighbours' owners (distinct ranks)",
                  (PetscReal)owners, (PetscReal)PetscMin(size, 3)));
  PetscCall(KergsStepperDestroy(&ref));
  PetscCall(KergsStepperDestroy(&tst));
  PetscFunctionReturn(0);
}

/* The repartitioning rule with the default options on a dense packing (confine500): the provisional geometric
   partition is replaced by METIS at the first check (step 10), nothing happens at the next check while the packing
   barely moves, and a repartition follows an imbalance (all grains moved onto rank 0) or a grown edge cut (the cut
   after the last partition halved by hand). On one rank nothing is ever repartitioned. */
static PetscErrorCode StepTo(KergsStepper st, PetscInt step)
{
  PetscFunctionBeginUser;
  while (st->scene->step < step) PetscCall(KergsStepperStep(st));
  PetscFunctionReturn(0);
}

static PetscErrorCode TestThresholds(void)
{
  KergsStepper   st;
  KergsPartition p;
  PetscMPIInt    size;
  PetscInt       cut_geometric, cut_metis, *order, *counts, n;
  PetscReal      imb_forced;
  PetscBool      valid;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(StepperWithExtra(PETSC_COMM_WORLD, "-options_file cases/confine500.opts -solver_type nlgs -solver_tol 1e-4 -solver_max_it 20",
                             NULL, &st));
  p = st->partition;
  n = st->scene->ndisks;
  PetscCall(StepTo(st, 10));
  cut_geometric = p->last.edgecut;
  PetscCall(StepTo(st, 11));
  cut_metis = p->last.edgecut;
  PetscCall(PetscPrintf(PETSC_COMM_WORLD,
                        "     thresholds: edge cut at step 10 (geometric) %" PetscInt_FMT ", at step 11 (after the check) %" PetscInt_FMT
                        " of %" PetscInt_FMT " edges; imbalance %.4f\n",
                        cut_geometric, cut_metis, p->last.edges, (double)p->last.imbalance));
  if (size == 1) {
    PetscCall(StepTo(st, 21));
    PetscCall(Check((PetscBool)(p->state.nrepartitions == 0 && p->state.nmoved == 0), "thresholds, 1 rank: never repartitioned",
                    (PetscReal)p->state.nrepartitions, 0));
    PetscCall(KergsStepperDestroy(&st));
    PetscFunctionReturn(0);
  }
  PetscCall(Check((PetscBool)(p->state.nrepartitions == 1 && p->state.last_method == KERGS_PARTITION_METIS),
                  "thresholds: METIS replaces the geometric partition at step 10", (PetscReal)p->state.nrepartitions, 1));
  PetscCall(Check((PetscBool)(cut_metis < cut_geometric), "thresholds: METIS edge cut below the geometric one", (PetscReal)cut_metis,
                  (PetscReal)cut_geometric));
  PetscCall(StepTo(st, 21));
  PetscCall(Check((PetscBool)(p->state.nrepartitions == 1), "thresholds: no repartition at step 20 (little change)",
                  (PetscReal)p->state.nrepartitions, 1));
  /* every grain onto rank 0 */
  PetscCall(PetscMalloc2(n, &order, size, &counts));
  for (PetscInt k = 0; k < n; k++) order[k] = k;
  for (PetscMPIInt q = 0; q < size; q++) counts[q] = q ? 0 : n;
  PetscCall(KergsPartitionRenumber(st->scene, st->contacts, order, counts, NULL));
  PetscCall(PetscFree2(order, counts));
  PetscCall(StepTo(st, 30));
  imb_forced = p->last.imbalance;
  PetscCall(StepTo(st, 31));
  PetscCall(Check((PetscBool)(p->state.nrepartitions == 2), "thresholds: imbalance (all on rank 0) repartitions at step 30",
                  (PetscReal)p->state.nrepartitions, 2));
  PetscCall(Check((PetscBool)(imb_forced > 1.5 && p->last.imbalance <= 1.10), "thresholds: imbalance back within 1.10", p->last.imbalance,
                  imb_forced));
  /* a cut that doubled since the last partition */
  p->state.edgecut_base = p->last.edgecut / 2;
  PetscCall(StepTo(st, 41));
  PetscCall(Check((PetscBool)(p->state.nrepartitions == 3), "thresholds: grown edge cut repartitions at step 40",
                  (PetscReal)p->state.nrepartitions, 3));
  PetscCall(LayoutIsValid(st, &valid));
  PetscCall(Check(valid, "thresholds: valid layout at the end", valid, 1));
  PetscCall(ReportPartition("thresholds", st));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* Measured work (-partition_work measured): a rank whose sweeps took twice the time per modelled unit counts that
   time as its work, and the next partition gives it less of the model (its grains weigh twice as much). The times are
   set by hand, so that the check is deterministic. */
static PetscErrorCode TestMeasuredWork(void)
{
  KergsStepper           st;
  KergsPartition         p;
  KergsPartitionMeasures m;
  PetscMPIInt            size, rank;
  PetscReal              before, after, tmax, tsum;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCallMPI(MPI_Comm_rank(PETSC_COMM_WORLD, &rank));
  if (size == 1) PetscFunctionReturn(0);
  PetscCall(StepperWithExtra(PETSC_COMM_WORLD, "-options_file cases/confine500.opts -solver_type nlgs -solver_tol 1e-4 -solver_max_it 20",
                             NULL, &st));
  p = st->partition;
  PetscCall(StepTo(st, 11));               /* METIS replaced the geometric partition at step 10 (modelled work: deterministic) */
  p->work = KERGS_PARTITION_WORK_MEASURED; /* from here on, with the times set below */
  PetscCall(KergsPartitionMeasure(p, st->scene, st->contacts, &m));
  before                   = m.my_work;
  p->state.compute_seconds = (rank == 0 ? 2e-9 : 1e-9) * m.my_work; /* rank 0: twice the time per unit */
  PetscCall(KergsPartitionMeasure(p, st->scene, st->contacts, &m));
  PetscCall(MPIU_Allreduce(&p->state.compute_seconds, &tmax, 1, MPIU_REAL, MPIU_MAX, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(&p->state.compute_seconds, &tsum, 1, MPIU_REAL, MPIU_SUM, PETSC_COMM_WORLD));
  PetscCall(Check((PetscBool)(PetscAbsReal(m.imbalance - tmax / (tsum / size)) < 1e-12), "measured work: imbalance of the times",
                  m.imbalance, tmax / (tsum / size)));
  PetscCall(Check((PetscBool)(rank == 0 ? p->state.work_scale > 1.2 : p->state.work_scale < 1.0),
                  "measured work: rank 0's factor above 1, the others' below", p->state.work_scale, rank == 0 ? 1.2 : 1.0));
  PetscCall(KergsPartitionApply(p, st->scene, st->contacts));
  PetscCall(KergsContactsDetect(st->contacts, st->scene)); /* the contacts of the new layout */
  p->state.compute_seconds = 0;                            /* the old times describe the old ownership */
  PetscCall(KergsPartitionMeasure(p, st->scene, st->contacts, &m));
  after = m.my_work;
  if (rank == 0)
    PetscCall(Check((PetscBool)(after < 0.85 * before), "measured work: the slow rank gets less modelled work", after, before));
  PetscCall(ReportPartition("measured work", st));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

/* The ghost layer around METIS's irregular parts: every ghost is within the reach 2 max R + alert + skin (plus the
   skin the grains may have moved since the build) of a disk owned here; a bounding-box test alone kept many more. */
static PetscErrorCode TestGhostsNearOwned(void)
{
  KergsStepper st;
  KergsScene   sc;
  PetscReal    rmax = 0, reach, worst = 0;
  PetscInt     far = 0;
  PetscMPIInt  size;

  PetscFunctionBeginUser;
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  if (size == 1) PetscFunctionReturn(0);
  PetscCall(StepperWithExtra(PETSC_COMM_WORLD,
                             "-options_file cases/confine500.opts -solver_type nlgs -solver_tol 1e-4 -solver_max_it 20 -ghost_skin 0.002",
                             NULL, &st));
  PetscCall(StepTo(st, 11)); /* METIS at step 10 */
  sc = st->scene;
  for (PetscInt i = 0; i < sc->nlocal; i++) rmax = PetscMax(rmax, sc->radius[i]);
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &rmax, 1, MPIU_REAL, MPIU_MAX, PETSC_COMM_WORLD));
  reach = 2 * rmax + sc->alert + 0.002;
  for (PetscInt g = sc->nowned; g < sc->nlocal; g++) {
    PetscReal dmin = PETSC_MAX_REAL;
    for (PetscInt i = 0; i < sc->nowned; i++) {
      PetscReal d2 = 0;
      for (PetscInt d = 0; d < KERGS_DIM; d++) d2 += PetscSqr(sc->x[KERGS_DIM * g + d] - sc->x[KERGS_DIM * i + d]);
      dmin = PetscMin(dmin, PetscSqrtReal(d2));
    }
    worst = PetscMax(worst, dmin / reach);
    far += dmin > reach + 0.002;
  }
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &far, 1, MPIU_INT, MPI_SUM, PETSC_COMM_WORLD));
  PetscCall(MPIU_Allreduce(MPI_IN_PLACE, &worst, 1, MPIU_REAL, MPIU_MAX, PETSC_COMM_WORLD));
  PetscCall(Check((PetscBool)(far == 0 && st->partition->state.last_method == KERGS_PARTITION_METIS),
                  "ghosts: each within reach of an owned disk (METIS parts)", worst, 1));
  PetscCall(ReportPartition("ghosts near owned", st));
  PetscCall(KergsStepperDestroy(&st));
  PetscFunctionReturn(0);
}

int main(int argc, char **argv)
{
  PetscMPIInt size;

  PetscCall(PetscInitialize(&argc, &argv, NULL, help));
  PetscCallMPI(MPI_Comm_size(PETSC_COMM_WORLD, &size));
  PetscCall(PetscPrintf(PETSC_COMM_WORLD, "partition tests on %d rank(s)\n", size));
  PetscCall(TestSamePhysics("confine5 frictionless, 1 vs n ranks", CONFINE5 "-steps 8", 8, 4));
  PetscCall(TestSamePhysics("deposit frictionless, 1 vs n ranks", DEPOSIT, 50, 50));
  PetscCall(TestGhostRebuilds());
  PetscCall(TestSamePhysics("confine500 frictionless, 1 vs n ranks",
                            "-options_file cases/confine500.opts -solver_type nlgs -solver_max_it 150 -solver_tol 1e-4 -steps 5 " TIGHT, 5,
                            5));
  PetscCall(TestRenumberingKeepsPhysics());
  PetscCall(TestMigrationKeepsImpulses(PETSC_TRUE));
  PetscCall(TestMigrationKeepsImpulses(PETSC_FALSE));
  PetscCall(TestRobustness());
  PetscCall(TestGrainOnThreeRanks());
  PetscCall(TestThresholds());
  PetscCall(TestMeasuredWork());
  PetscCall(TestGhostsNearOwned());
  PetscCall(PetscOptionsClear(NULL));
  {
    int code = Finish();
    PetscCall(PetscFinalize());
    return code;
  }
}
