#pragma once
// Sampled analytic test shapes for the tests: the functions live in the library
// (include/chokeloops/field/analytic.h) so that bench/ can use them too.
#include "chokeloops/field/analytic.h"
