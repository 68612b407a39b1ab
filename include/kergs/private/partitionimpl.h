/* kergs partition, private: the partition object's fields, for src/partition/ only; other components go through
   kergs/partition.h. */
#ifndef KERGS_PARTITIONIMPL_H
#define KERGS_PARTITIONIMPL_H

#include <kergs/partition.h>

struct _p_KergsPartition {
  MPI_Comm           comm;
  KergsPartitionType type;
  PetscReal          imbalance_tol;  /* -partition_imbalance_tol (default 1.10) */
  PetscReal          edgecut_growth; /* -partition_edgecut_growth (default 1.25) */
  PetscInt           check_every;    /* -partition_check_every: steps between checks (0: never) */
  PetscViewer        viewer;         /* -partition_view [viewer]: one line per rank and step, and the view at the end */
  PetscViewerFormat  view_format;
  PetscInt           metis_seed;  /* -partition_metis_seed */
  PetscBool          metis_curve; /* -partition_metis_curve: Hilbert-curve edges in METIS's graph */
  KergsPartitionWork work;        /* -partition_work (default model) */
  /* state: what a checkpoint keeps (KergsPartitionGetState)
     initialized: the initial partition was done; provisional: type metis, METIS not run yet (replaced once the graph is
     dense enough); edgecut_base: edge cut right after the last partition (-1: unknown, set at the next check);
     imbalance_base: imbalance right after the last partition, on the graph it was computed from; nrepartitions:
     partitions computed after the initial one; nmoved: grains that changed rank, summed over every partition;
     last_method: method of the latest partition (a KergsPartitionType); compute_seconds: this rank's time in the
     sweeps' arithmetic at the last step (KergsPartitionRecord); work_scale: measured work, this rank's time per
     modelled unit over the mean (KergsPartitionMeasure) */
  KergsPartitionState    state;
  PetscLogDouble         seconds; /* time spent partitioning and renumbering */
  KergsPartitionMeasures last;    /* latest measures (KergsPartitionRecord) */
};

/* Shared by the partition's files. */
/* Work of a contact in a step, for each of its disks: the sweeps dominate a step (thousands per step), and there an
   active contact costs about 6 times an inactive one, whose zero impulse is skipped (docs/scaling.md, "Partition
   work"). Each disk counts 1 more for its own work outside the sweeps. */
#define KERGS_WORK_INACTIVE 1
#define KERGS_WORK_ACTIVE 6
static inline PetscInt KergsPartitionContactWork(const KergsActivity *act, const KergsContact *c)
{
  return KergsContactIsActive(act, c) ? KERGS_WORK_ACTIVE : KERGS_WORK_INACTIVE;
}

/* What rank 0 computed besides the order, known to every rank after KergsPartitionComputeOrder. */
typedef struct {
  PetscInt  method;      /* the method used (a KergsPartitionType) */
  PetscInt  edgecut;     /* cut of the new partition on the graph it was computed from (-1: graph without edges) */
  PetscInt  status;      /* METIS status (METIS_OK = 1) */
  PetscInt  metis_tried; /* METIS ran (its result may have been replaced by the geometric one) */
  PetscReal imbalance;   /* imbalance of the new partition with the graph's work */
} KergsPartitionOutcome;

/* Collective (src/partition/graph.c): the grain graph gathered on rank 0 and cut there by the type of p. On rank 0,
   order (ndisks entries) is the new order of the disks (new index k holds old disk order[k]); on every rank, counts[q]
   is the number of disks of rank q (2 size entries: the second half is workspace) and *out the outcome. A failure of
   METIS is an error on every rank. */
PETSC_INTERN PetscErrorCode KergsPartitionComputeOrder(KergsPartition, KergsScene, KergsContacts, const PetscInt oldranges[],
                                                       PetscInt order[], PetscInt counts[], KergsPartitionOutcome *);

#endif
