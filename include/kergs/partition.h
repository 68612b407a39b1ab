/* kergs partition: which rank owns which grain (docs/design.md: parallel layout).

   Rank p owns the disks of the contiguous global index range [dstart, dend), so a partition is a new numbering of
   the disks: the grains of part 0 first, then those of part 1, and so on; the disks then MIGRATE to their new
   owners with their whole state (KergsSceneMigrate). Grain ids (scene->id) are persistent and travel with the
   grains; so do the contact impulses (warm start).

   Types (-partition_type):
     contiguous  the even split of KergsSceneSetDisks, never changed
     geometric   sort by a Hilbert space-filling-curve key of the centres, cut into chunks of equal work; inside
                 a part the disks keep their index order (the sweeps' Gauss-Seidel order), as with metis
     metis       METIS k-way on the grain graph (vertices: grains, weighted by their work; edges: disk-disk
                 contacts), recomputed when the work imbalance or the edge cut grows past the thresholds. The
                 initial partition (no contacts yet) and partitions of graphs too sparse to describe the packing
                 (mean degree below KERGS_PARTITION_MIN_DEGREE) are geometric; such a partition is provisional and
                 replaced by METIS at the first check where the graph is dense enough. METIS runs on rank 0 (the
                 graph is gathered there, the new order broadcast), with a fixed seed, on the graph in grain-id order
                 (so that a graph that changed little gets a similar partition), and with light edges along the
                 Hilbert curve (-partition_metis_curve) so that grains without contacts stay with their neighbours.
                 When METIS misses the imbalance tolerance (tiny graphs) and the geometric partition meets it, or
                 METIS leaves a rank without grains and the geometric partition does not, the geometric one is used. Parts are matched to
   the ranks that own most of their grains already. On one rank nothing is ever renumbered (every type is then the contiguous one).

   Measures: the work of a grain is 1 + the work of each of its contacts (disk-disk and disk-wall), 6 for an active
   contact and 1 for an inactive one (partitionimpl.h, KergsPartitionContactWork: their costs in a sweep); the work of a
   rank is the sum over the grains it owns (-partition_work model, the default). With -partition_work measured the work of a rank is instead
   its time in the sweeps' arithmetic at the last step (messages and reductions excluded), once every rank has timed some, and METIS weighs
   each grain by the model times its rank's time per modelled unit: what the model misses (docs/scaling.md, "Partition work") is balanced at
   the next check. imbalance = max over ranks of the work / mean work. The edge cut is the number of disk-disk contacts whose grains are
   owned by different ranks. The ghosts of a rank are those of its current ghost layer (src/scene/ghosts.c). */
#ifndef KERGS_PARTITION_H
#define KERGS_PARTITION_H

#include <kergs/detect.h>

typedef enum { KERGS_PARTITION_CONTIGUOUS, KERGS_PARTITION_GEOMETRIC, KERGS_PARTITION_METIS } KergsPartitionType;
PETSC_EXTERN const char *const KergsPartitionTypes[];

/* How the work of a rank is counted (-partition_work). */
typedef enum {
  KERGS_PARTITION_WORK_MODEL,   /* per grain 1 + per contact 6 (active) or 1 (inactive): deterministic */
  KERGS_PARTITION_WORK_MEASURED /* the rank's time in the sweeps' arithmetic at the last step (the model until timed) */
} KergsPartitionWork;
PETSC_EXTERN const char *const KergsPartitionWorks[];

/* A METIS partition needs a contact graph of at least this mean degree (2 edges / grains); below, geometric. */
#define KERGS_PARTITION_MIN_DEGREE 1.0
/* Weight of a contact edge in METIS's graph, against 1 for an edge between consecutive grains along the Hilbert
   curve (-partition_metis_curve). */
#define KERGS_PARTITION_CONTACT_WEIGHT 8

/* Measures of the current partition (global, the same on every rank, except the per-rank fields). */
typedef struct {
  PetscInt  edgecut;         /* disk-disk contacts between grains of different ranks */
  PetscInt  ghosts;          /* sum over ranks of their ghost grains */
  PetscReal imbalance;       /* max rank work / mean rank work (1 when there is no work) */
  PetscReal imbalance_bound; /* lower bound of any partition's imbalance: max(1, ranks / grains) */
  PetscReal work_max, work_mean;
  PetscInt  edges; /* disk-disk contacts (edges of the grain graph) */
  /* this rank */
  PetscInt  my_grains, my_contacts, my_ghosts;
  PetscReal my_work;      /* modelled */
  PetscReal my_seconds;   /* measured: time in the sweeps' arithmetic at the last step */
  PetscInt  repartitions; /* partitions computed after the initial one, so far */
} KergsPartitionMeasures;

/* Repartitioning rule, checked every check_every steps: repartition when
     imbalance >= imbalance_tol * imbalance_bound and imbalance > imbalance_base (it grew since the last partition;
       with imbalance_tol = 1 the second condition is dropped: a repartition at every check), or
     edgecut > edgecut_growth * max(edgecut_base, 1), or
     the partition is provisional and the graph is dense enough for METIS. */
typedef struct _p_KergsPartition *KergsPartition;

PETSC_EXTERN PetscErrorCode KergsPartitionCreate(MPI_Comm, KergsPartition *);
/* -partition_type, -partition_imbalance_tol, -partition_edgecut_growth, -partition_check_every, -partition_view,
   -partition_metis_curve, -partition_metis_seed. Default type: metis on more than one rank, contiguous on one. */
PETSC_EXTERN PetscErrorCode KergsPartitionSetFromOptions(KergsPartition);
/* Collective. Compute a partition of the scene's disks with the object's type (contiguous: the even split; metis
   falls back to geometric on a sparse graph or with more ranks than grains) from the contacts' graph, and
   renumber the scene and the contacts accordingly. No-op on one rank. */
PETSC_EXTERN PetscErrorCode KergsPartitionApply(KergsPartition, KergsScene, KergsContacts);
/* Collective; the time-loop hook, called before each step's detection: the initial partition at the first call,
   then every check_every steps (scene->step a multiple of it) measure the partition with the contacts of the
   previous step and repartition when past the thresholds (or when provisional). repartitioned (may be NULL):
   whether the disks were renumbered, the initial partition included (the same on every rank). */
PETSC_EXTERN PetscErrorCode KergsPartitionUpdate(KergsPartition, KergsScene, KergsContacts, PetscBool *repartitioned);
/* Collective: edge cut, work imbalance, ghosts, per-rank counts of the current partition and contacts. */
PETSC_EXTERN PetscErrorCode KergsPartitionMeasure(KergsPartition, KergsScene, KergsContacts, KergsPartitionMeasures *);
/* Collective, after each step's solve: measure the partition (into *m, may be NULL), keep this rank's time in the
   sweeps' arithmetic (compute_seconds, for -partition_work measured), and with -partition_view print one line per
   rank (grains, ghosts, contacts, work, sweep_seconds: this rank's sweep time, compute_seconds: its arithmetic in
   them) and one summary line. */
PETSC_EXTERN PetscErrorCode KergsPartitionObserve(KergsPartition, KergsScene, KergsContacts, PetscReal sweep_seconds,
                                                  PetscReal compute_seconds, KergsPartitionMeasures *m);
/* The viewer of -partition_view (NULL when not given): the stepper views the partition there at the end of the run */
PETSC_EXTERN PetscErrorCode KergsPartitionGetView(KergsPartition, PetscViewer *);
PETSC_EXTERN PetscErrorCode KergsPartitionView(KergsPartition, PetscViewer);
PETSC_EXTERN PetscErrorCode KergsPartitionDestroy(KergsPartition *);

/* What a checkpoint keeps of the partition, so that a run restarted on the same number of ranks repartitions at the
   same steps and in the same way as if never stopped (the check counter is the scene's step). */
typedef struct {
  PetscBool initialized, provisional;
  PetscInt  edgecut_base, nrepartitions, nmoved, last_method;
  PetscReal imbalance_base;
  PetscReal compute_seconds, work_scale; /* this rank's (-partition_work measured) */
} KergsPartitionState;
PETSC_EXTERN PetscErrorCode KergsPartitionGetState(KergsPartition, KergsPartitionState *);
/* Restores a state of the same number of ranks; NULL: the state of a new run (the next KergsPartitionUpdate computes the
   initial partition), for a restart on another number of ranks. */
PETSC_EXTERN PetscErrorCode KergsPartitionSetState(KergsPartition, const KergsPartitionState *);

/* Collective, the migration itself: renumber the disks so that new global index k holds old disk order[k]; rank p
   then owns counts[p] disks, after those of ranks 0 .. p-1. order (a permutation of 0 .. ndisks-1) and counts (one
   per rank, summing to ndisks) must be the same on every rank. The disks move to their new owners with their
   state (KergsSceneMigrate, which drops the ghost layer: rebuild it with KergsSceneUpdateGhosts), and the contacts
   are moved to the new owners of their disk a, left as the current list holding only their keys (a, kind, idb)
   and impulses, so that the next detection carries their impulses over. Returns the number of grains that changed
   rank (global) in nmoved (may be NULL). */
PETSC_EXTERN PetscErrorCode KergsPartitionRenumber(KergsScene, KergsContacts, const PetscInt order[], const PetscInt counts[],
                                                   PetscInt *nmoved);

#endif
