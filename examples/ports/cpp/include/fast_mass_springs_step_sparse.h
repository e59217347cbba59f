// One of the three functions of the CSC317 mass-spring assignment, with the assignment's
// signature (see signed_incidence_matrix_sparse.h).
#ifndef CLOTHSIM_FAST_MASS_SPRINGS_STEP_SPARSE_H
#define CLOTHSIM_FAST_MASS_SPRINGS_STEP_SPARSE_H
#include <Eigen/Core>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

// One step: y = 2 Ucur - Uprev, 50 local/global iterations starting from Ucur; pins held at
// their rest positions V by the penalty w = 1e10; external force fext (n x 3) [N]. On entry
// Unext holds the current positions, as in the assignment's main.cpp (a copy of Ucur).
void fast_mass_springs_step_sparse(const Eigen::MatrixXd & V, const Eigen::MatrixXi & E, const double k, const Eigen::VectorXi & b, const double delta_t, const Eigen::MatrixXd & fext, const Eigen::VectorXd & r, const Eigen::SparseMatrix<double> & M, const Eigen::SparseMatrix<double> & A, const Eigen::SparseMatrix<double> & C, const Eigen::SimplicialLLT<Eigen::SparseMatrix<double> > & prefactorization, const Eigen::MatrixXd & Uprev, const Eigen::MatrixXd & Ucur, Eigen::MatrixXd & Unext);
#endif
