/* The tests look inside the objects they test, as PETSc's own tests do: the public API of every component, and its
   private fields (include/kergs/private/). The library's components themselves never include another's private
   header (tests/check_layout.sh). */
#ifndef KERGS_TESTS_INTERNALS_H
#define KERGS_TESTS_INTERNALS_H

#include <kergs/kergs.h>
#include <kergs/kernel.h>
#include <kergs/predictor.h>
#include <kergs/private/sceneimpl.h>
#include <kergs/private/detectimpl.h>
#include <kergs/private/operatorsimpl.h>
#include <kergs/private/sweepimpl.h>
#include <kergs/private/kernelimpl.h>
#include <kergs/private/predictorimpl.h>
#include <kergs/private/solverimpl.h>
#include <kergs/private/partitionimpl.h>
#include <kergs/private/resultsimpl.h>
#include <kergs/private/stepperimpl.h>

#endif
