// clothsim's driver for the solver of sam007961/FastMassSpring (MIT License, Samer Itani).
//
// The port's source is not part of clothsim: benchmarks/cpp_side_by_side.py downloads its
// MassSpringSolver.{h,cpp} at a pinned commit (each file checked against its SHA-256) and
// compiles them with this file only (no OpenGL viewer):
//
//   g++ -O3 -DNDEBUG -std=c++17 -I/usr/include/eigen3 -I<port>/ClothApp \
//       driver.cpp <port>/ClothApp/MassSpringSolver.cpp -o fastmassspring_driver
//
// Usage: fastmassspring_driver SCENE ITERATIONS
//
// SCENE is the text file the benchmark writes from a clothsim model (scene_format below),
// so both programs step the same vertices, springs, masses, forces, time step and pins.
// The port has no pin inside its solve: its app puts fixed points back after every step
// (CgPointFixNode). Here a pinned vertex also gets the mass PIN_MASS and no external force,
// so the solve itself holds it (to about PIN_MASS^-1 of a spring force) and the free vertices
// see a fixed point, as clothsim's exact pins are; CgPointFixNode then puts it back exactly.
//
// After setup the driver prints "ready <setup seconds>" and answers commands on stdin, one
// per line, each answered by one line on stdout:
//   steps K      K steps (MassSpringSolver::solve(ITERATIONS), then the pins put back);
//                answers "times c1 w1 c2 w2 ..." per step: c = thread CPU seconds, w = wall
//                seconds of the solve call alone
//   write PATH   writes the positions (one vertex per line, x y z); answers "written"
//   state PREV NOW  sets the state from two such files, x_{n-1} and x_n: the solver keeps
//                x_{n-1} privately, so it is set by solve(0) (which stores the positions
//                as the previous ones and iterates nothing) between the two; answers "set"
//   quit         ends the program
#include "MassSpringSolver.h"

#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

// the mass of a pinned vertex [kg]: about 1e8 times a cloth's total, far above any spring
// coupling h^2 k it meets, and still exact enough in float (the pins are put back after
// each step anyway)
const float PIN_MASS = 1e8f;

// scene_format 1 (all numbers in SI units, one record per line):
//   clothsim-fastmassspring-scene 1
//   <n_points> <n_springs> <n_pins>
//   <h> <damping a>
//   n_points lines: x y z mass fx fy fz
//   n_springs lines: i j rest_length stiffness
//   n_pins lines: vertex index
struct Scene {
    unsigned int n_points = 0, n_springs = 0, n_pins = 0;
    float h = 0.0f, damping = 1.0f;
    std::vector<float> positions;
    Eigen::VectorXf masses, fext, rest_lengths, stiffnesses;
    mass_spring_system::EdgeList springs;
    std::vector<unsigned int> pins;
};

[[noreturn]] void fail(const std::string& what) {
    throw std::runtime_error(what);
}

Scene read_scene(const char* path) {
    std::ifstream in(path);
    if (!in) fail(std::string("cannot open scene ") + path);
    std::string magic;
    int version = 0;
    in >> magic >> version;
    if (magic != "clothsim-fastmassspring-scene" || version != 1)
        fail(std::string(path) + ": not a clothsim-fastmassspring-scene 1 file");
    Scene s;
    in >> s.n_points >> s.n_springs >> s.n_pins >> s.h >> s.damping;
    if (!in || s.n_points == 0) fail(std::string(path) + ": bad header");
    s.positions.resize(3 * s.n_points);
    s.masses.resize(s.n_points);
    s.fext.resize(3 * s.n_points);
    for (unsigned int i = 0; i < s.n_points; i++) {
        in >> s.positions[3 * i] >> s.positions[3 * i + 1] >> s.positions[3 * i + 2]
           >> s.masses[i] >> s.fext[3 * i] >> s.fext[3 * i + 1] >> s.fext[3 * i + 2];
    }
    s.springs.resize(s.n_springs);
    s.rest_lengths.resize(s.n_springs);
    s.stiffnesses.resize(s.n_springs);
    for (unsigned int k = 0; k < s.n_springs; k++) {
        in >> s.springs[k].first >> s.springs[k].second >> s.rest_lengths[k]
           >> s.stiffnesses[k];
        if (s.springs[k].first >= s.n_points || s.springs[k].second >= s.n_points)
            fail(std::string(path) + ": spring " + std::to_string(k) + " names no vertex");
    }
    s.pins.resize(s.n_pins);
    for (unsigned int p = 0; p < s.n_pins; p++) {
        in >> s.pins[p];
        if (s.pins[p] >= s.n_points) fail(std::string(path) + ": pin names no vertex");
    }
    if (!in) fail(std::string(path) + ": ends early or holds a non-number");
    return s;
}

double thread_seconds() {
    timespec t;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

double wall_seconds() {
    using clock = std::chrono::steady_clock;
    return std::chrono::duration<double>(clock::now().time_since_epoch()).count();
}

void write_positions(const std::string& path, const std::vector<float>& x) {
    std::ofstream out(path);
    if (!out) fail("cannot write " + path);
    char line[96];
    for (size_t i = 0; i + 2 < x.size(); i += 3) {
        std::snprintf(line, sizeof line, "%.9g %.9g %.9g\n", x[i], x[i + 1], x[i + 2]);
        out << line;
    }
    if (!out.flush()) fail("cannot write " + path);
}

void read_positions(const std::string& path, std::vector<float>& x) {
    std::ifstream in(path);
    if (!in) fail("cannot open " + path);
    for (float& value : x) in >> value;
    if (!in) fail(path + ": fewer positions than vertices");
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::cerr << "usage: " << argv[0] << " SCENE ITERATIONS\n";
        return 2;
    }
    try {
        Scene s = read_scene(argv[1]);
        const int iterations = std::stoi(argv[2]);
        if (iterations < 1) fail("ITERATIONS must be at least 1");
        for (unsigned int p : s.pins) {
            s.masses[p] = PIN_MASS;
            for (int c = 0; c < 3; c++) s.fext[3 * p + c] = 0.0f;
        }
        const double c0 = thread_seconds();
        mass_spring_system system(s.n_points, s.n_springs, s.h, s.springs, s.rest_lengths,
                                  s.stiffnesses, s.masses, s.fext, s.damping);
        // the solver maps this buffer as its state (as the port's app maps its mesh)
        std::vector<float>& vbuff = s.positions;
        MassSpringSolver solver(&system, vbuff.data());
        CgRootNode root(&system, vbuff.data());
        CgPointFixNode pins(&system, vbuff.data());
        for (unsigned int p : s.pins) pins.fixPoint(p);
        root.addChild(&pins);
        CgSatisfyVisitor satisfy;
        std::cout << "ready " << thread_seconds() - c0 << std::endl;

        std::string line;
        while (std::getline(std::cin, line)) {
            std::istringstream cmd(line);
            std::string word;
            cmd >> word;
            if (word == "quit") break;
            if (word == "steps") {
                int k = 0;
                cmd >> k;
                std::ostringstream answer;
                answer << "times";
                answer.precision(9);
                for (int i = 0; i < k; i++) {
                    const double w = wall_seconds(), c = thread_seconds();
                    solver.solve(iterations);
                    const double c1 = thread_seconds(), w1 = wall_seconds();
                    satisfy.satisfy(root);
                    answer << ' ' << c1 - c << ' ' << w1 - w;
                }
                std::cout << answer.str() << std::endl;
            } else if (word == "state") {
                std::string prev, now;
                cmd >> prev >> now;
                read_positions(prev, vbuff);
                solver.solve(0);
                read_positions(now, vbuff);
                std::cout << "set" << std::endl;
            } else if (word == "write") {
                std::string path;
                cmd >> path;
                write_positions(path, vbuff);
                std::cout << "written" << std::endl;
            } else {
                fail("unknown command: " + line);
            }
        }
    } catch (const std::exception& e) {
        std::cerr << "fastmassspring_driver: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
