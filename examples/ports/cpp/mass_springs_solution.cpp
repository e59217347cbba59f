// The project's own solution of the three assignment functions (mass_springs.h).
#include "mass_springs.h"

#include <vector>

void signed_incidence_matrix_sparse(const int n, const Eigen::MatrixXi & E, Eigen::SparseMatrix<double> & A)
{
  std::vector<Eigen::Triplet<double> > ijv;
  for(int e = 0; e < E.rows(); e++)
  {
    ijv.emplace_back(e, E(e, 0), 1.0);
    ijv.emplace_back(e, E(e, 1), -1.0);
  }
  A.resize(E.rows(), n);
  A.setFromTriplets(ijv.begin(), ijv.end());
}

bool fast_mass_springs_precomputation_sparse(const Eigen::MatrixXd & V, const Eigen::MatrixXi & E, const double k, const Eigen::VectorXd & m, const Eigen::VectorXi & b, const double delta_t, Eigen::VectorXd & r, Eigen::SparseMatrix<double> & M, Eigen::SparseMatrix<double> & A, Eigen::SparseMatrix<double> & C, Eigen::SimplicialLLT<Eigen::SparseMatrix<double> > & prefactorization)
{
  const int n = V.rows();
  r.resize(E.rows());
  for(int e = 0; e < E.rows(); e++) r(e) = (V.row(E(e, 0)) - V.row(E(e, 1))).norm();
  std::vector<Eigen::Triplet<double> > ijv;
  for(int i = 0; i < n; i++) ijv.emplace_back(i, i, m(i));
  M.resize(n, n);
  M.setFromTriplets(ijv.begin(), ijv.end());
  signed_incidence_matrix_sparse(n, E, A);
  ijv.clear();
  for(int i = 0; i < b.size(); i++) ijv.emplace_back(i, b(i), 1.0);
  C.resize(b.size(), n);
  C.setFromTriplets(ijv.begin(), ijv.end());
  const double w = 1e10;
  Eigen::SparseMatrix<double> Q = k * A.transpose() * A;
  Q += M / (delta_t * delta_t);
  Q += w * C.transpose() * C;
  prefactorization.compute(Q);
  return prefactorization.info() == Eigen::Success;
}

void fast_mass_springs_step_sparse(const Eigen::MatrixXd & V, const Eigen::MatrixXi & E, const double k, const Eigen::VectorXi & b, const double delta_t, const Eigen::MatrixXd & fext, const Eigen::VectorXd & r, const Eigen::SparseMatrix<double> & M, const Eigen::SparseMatrix<double> & A, const Eigen::SparseMatrix<double> & C, const Eigen::SimplicialLLT<Eigen::SparseMatrix<double> > & prefactorization, const Eigen::MatrixXd & Uprev, const Eigen::MatrixXd & Ucur, Eigen::MatrixXd & Unext)
{
  (void)b;  // C already selects the pinned rows
  const double w = 1e10;
  const Eigen::MatrixXd y = 2.0 * Ucur - Uprev;
  const Eigen::MatrixXd l = M * y / (delta_t * delta_t) + fext + w * C.transpose() * (C * V);
  Unext = Ucur;
  Eigen::MatrixXd d(E.rows(), 3);
  for(int iter = 0; iter < 50; iter++)
  {
    const Eigen::MatrixXd p = A * Unext;  // spring vectors x_a - x_b
    for(int e = 0; e < E.rows(); e++) d.row(e) = r(e) * p.row(e).normalized();
    Unext = prefactorization.solve(k * A.transpose() * d + l);
  }
}
