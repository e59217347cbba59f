// The three functions of the mass-spring assignment of the University of Toronto's CSC317
// (A. Jacobson, "computer-graphics-mass-spring-systems"), sparse versions, with the
// assignment's signatures, one header each in include/ under the assignment's names.
// assignment_driver.cpp calls them; mass_springs_solution.cpp is the project's own solution
// (a student's files defining them replace it: make SOLUTION=... [SOLUTION_INCLUDE=...]).
#pragma once

#include "signed_incidence_matrix_sparse.h"
#include "fast_mass_springs_precomputation_sparse.h"
#include "fast_mass_springs_step_sparse.h"
