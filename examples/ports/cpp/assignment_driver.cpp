// assignment_driver MODEL_DIR OUT_DIR [--frames F]: runs the CSC317 mass-spring assignment's
// three functions (mass_springs.h) on a `clothsim export` model folder, as the assignment's
// main.cpp does (one k, penalty pins w = 1e10 at the rest positions, y = 2 Ucur - Uprev,
// 50 iterations from Ucur; Unext holds the current positions on entry), and writes
// OUT_DIR/positions.txt and velocities.txt.
#include <filesystem>
#include <iostream>
#include <string>

#include "mass_springs.h"
#include "model_io.h"

using namespace clothsim_port;

int main(int argc, char** argv) {
  if (argc != 3 && !(argc == 5 && std::string(argv[3]) == "--frames")) {
    std::cerr << "usage: assignment_driver MODEL_DIR OUT_DIR [--frames F]\n";
    return 2;
  }
  try {
    Model m = read_model(argv[1]);
    const double h = setting(m, "h", NAN);
    const int frames = argc == 5 ? std::stoi(argv[4]) : static_cast<int>(setting(m, "frames", NAN));
    auto refuse = [](const std::string& why) { throw ReadError(why); };
    Eigen::MatrixXi E(m.a.size(), 2);
    for (size_t e = 0; e < m.a.size(); ++e) {
      if (m.k[e] != m.k[0]) refuse("springs.txt: the assignment has one stiffness k; the model has " + std::to_string(m.k[0]) + " and " + std::to_string(m.k[e]) + " N/m");
      if (std::abs(m.r[e] - (m.V.row(m.a[e]) - m.V.row(m.b[e])).norm()) > 1e-12 * (1 + m.r[e])) refuse("springs.txt: spring " + std::to_string(e) + "'s rest length is not its initial length (the assignment computes r from V)");
      E(e, 0) = m.a[e], E(e, 1) = m.b[e];
    }
    Eigen::VectorXi b(m.pins.size());
    for (size_t i = 0; i < m.pins.size(); ++i) {
      const Pin& p = m.pins[i];
      if (p.method != 1 || p.stiffness != 1e10) refuse("pins.txt: the assignment pins by a penalty of w = 1e10 N/m; vertex " + std::to_string(p.vertex) + " is pinned " + (p.method ? "by w = " + std::to_string(p.stiffness) + " N/m" : "exactly"));
      if (Eigen::RowVector3d(p.x, p.y, p.z) != m.V.row(p.vertex)) refuse("pins.txt: vertex " + std::to_string(p.vertex) + "'s pin target is not its rest position");
      b(i) = p.vertex;
    }
    Eigen::VectorXd r;
    Eigen::SparseMatrix<double> M, A, C;
    Eigen::SimplicialLLT<Eigen::SparseMatrix<double> > prefactorization;
    const double k = m.k.empty() ? 0.0 : m.k[0];
    if (!fast_mass_springs_precomputation_sparse(m.V, E, k, m.mass, b, h, r, M, A, C, prefactorization)) refuse("the precomputation failed (the system is not positive definite)");
    std::filesystem::create_directories(argv[2]);
    TrajectoryWriter out(argv[2]);
    // as the assignment's main.cpp: U holds the positions, the step gets a copy of them as
    // Ucur and U itself as Unext (so Unext holds the current positions on entry, never an
    // empty matrix), and Uprev becomes that copy
    Eigen::MatrixXd U = m.V, Uprev = m.V - h * m.V0;
    out.frame(U, m.V0);
    for (int f = 0; f < frames; ++f) {
      const Eigen::MatrixXd U_stash = U;
      fast_mass_springs_step_sparse(m.V, E, k, b, h, m.force, r, M, A, C, prefactorization, Uprev, U_stash, U);
      if (U.rows() != U_stash.rows() || U.cols() != 3) refuse("fast_mass_springs_step_sparse: Unext has " + std::to_string(U.rows()) + " x " + std::to_string(U.cols()) + " entries after step " + std::to_string(f + 1) + ", expected " + std::to_string(U_stash.rows()) + " x 3");
      out.frame(U, ((U - U_stash) / h).eval());
      Uprev = U_stash;
    }
  } catch (const std::exception& e) {
    std::cerr << "assignment_driver: " << e.what() << "\n";
    return 2;
  }
  return 0;
}
