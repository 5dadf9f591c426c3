#pragma once
// Sampled analytic test shapes for the tests: the functions live in the library
// (include/chokeloops/analytic.h) so that bench/ can use them too.
#include "chokeloops/analytic.h"
