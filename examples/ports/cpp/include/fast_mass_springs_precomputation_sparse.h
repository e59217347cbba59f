// One of the three functions of the CSC317 mass-spring assignment, with the assignment's
// signature (see signed_incidence_matrix_sparse.h).
#ifndef CLOTHSIM_FAST_MASS_SPRINGS_PRECOMPUTATION_SPARSE_H
#define CLOTHSIM_FAST_MASS_SPRINGS_PRECOMPUTATION_SPARSE_H
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

// Rest lengths r from V, mass matrix M = diag(m), incidence A, pin selection C (|b| x n), and
// the prefactorization of k A^T A + M / delta_t^2 + w C^T C (w = 1e10). Returns success.
bool fast_mass_springs_precomputation_sparse(const Eigen::MatrixXd & V, const Eigen::MatrixXi & E, const double k, const Eigen::VectorXd & m, const Eigen::VectorXi & b, const double delta_t, Eigen::VectorXd & r, Eigen::SparseMatrix<double> & M, Eigen::SparseMatrix<double> & A, Eigen::SparseMatrix<double> & C, Eigen::SimplicialLLT<Eigen::SparseMatrix<double> > & prefactorization);
#endif
