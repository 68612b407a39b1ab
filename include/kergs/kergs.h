/* kergs: Non-Smooth Contact Dynamics of dense granular media on PETSc.
   Umbrella header: every public component of libkergs. */
#ifndef KERGS_H
#define KERGS_H

#include <kergs/base.h>
#include <kergs/scene.h>
#include <kergs/detect.h>
#include <kergs/operators.h>
#include <kergs/law.h>
#include <kergs/sweep.h>
#include <kergs/kernel.h>
#include <kergs/predictor.h>
#include <kergs/solver.h>
#include <kergs/results.h>
#include <kergs/xdmf.h>
#include <kergs/sample.h>
#include <kergs/fclib.h>
#include <kergs/files.h>
#include <kergs/checkpoint.h>
#include <kergs/partition.h>
#include <kergs/stepper.h>

#endif
