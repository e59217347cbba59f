// One of the three functions of the CSC317 mass-spring assignment (A. Jacobson,
// "computer-graphics-mass-spring-systems"), with the assignment's signature: a solution's
// file includes this header by this name (a solution's own include folder may replace it:
// make SOLUTION_INCLUDE=...).
#ifndef CLOTHSIM_SIGNED_INCIDENCE_MATRIX_SPARSE_H
#define CLOTHSIM_SIGNED_INCIDENCE_MATRIX_SPARSE_H
#include <Eigen/Core>
#include <Eigen/Sparse>

// A (|E| x n): row e has +1 in column E(e,0) and -1 in column E(e,1).
void signed_incidence_matrix_sparse(const int n, const Eigen::MatrixXi & E, Eigen::SparseMatrix<double> & A);
#endif
