// The three functions of the mass-spring assignment of the University of Toronto's CSC317
// (A. Jacobson, "computer-graphics-mass-spring-systems"), sparse versions, with the
// assignment's signatures. assignment_driver.cpp calls them; mass_springs_solution.cpp is
// the project's own solution (a student's file defining them replaces it: make SOLUTION=...).
#pragma once

#include <Eigen/Core>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

// A (|E| x n): row e has +1 in column E(e,0) and -1 in column E(e,1).
void signed_incidence_matrix_sparse(const int n, const Eigen::MatrixXi & E, Eigen::SparseMatrix<double> & A);

// Rest lengths r from V, mass matrix M = diag(m), incidence A, pin selection C (|b| x n), and
// the prefactorization of k A^T A + M / delta_t^2 + w C^T C (w = 1e10). Returns success.
bool fast_mass_springs_precomputation_sparse(const Eigen::MatrixXd & V, const Eigen::MatrixXi & E, const double k, const Eigen::VectorXd & m, const Eigen::VectorXi & b, const double delta_t, Eigen::VectorXd & r, Eigen::SparseMatrix<double> & M, Eigen::SparseMatrix<double> & A, Eigen::SparseMatrix<double> & C, Eigen::SimplicialLLT<Eigen::SparseMatrix<double> > & prefactorization);

// One step: y = 2 Ucur - Uprev, 50 local/global iterations starting from Ucur; pins held at
// their rest positions V by the penalty w = 1e10; external force fext (n x 3) [N].
void fast_mass_springs_step_sparse(const Eigen::MatrixXd & V, const Eigen::MatrixXi & E, const double k, const Eigen::VectorXi & b, const double delta_t, const Eigen::MatrixXd & fext, const Eigen::VectorXd & r, const Eigen::SparseMatrix<double> & M, const Eigen::SparseMatrix<double> & A, const Eigen::SparseMatrix<double> & C, const Eigen::SimplicialLLT<Eigen::SparseMatrix<double> > & prefactorization, const Eigen::MatrixXd & Uprev, const Eigen::MatrixXd & Ucur, Eigen::MatrixXd & Unext);
