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

#endif
