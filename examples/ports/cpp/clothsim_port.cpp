// clothsim_port: a small C++17/Eigen port of the local/global mass-spring method
// (Liu, Bargteil, O'Brien, Kavan 2013), to be checked by `clothsim check`.
//
// Reads the model folder `clothsim export` writes and writes positions.txt / velocities.txt
// (one frame a line, 3n numbers, %.17g; frame 0 is the initial state). See README.md and
// `clothsim_port --help`. Each step, with y = x_n + h v_n and a fixed iteration count:
//   local   d_i = r_i (x_a - x_b) / |x_a - x_b|
//   global  (M + h^2 L) x = M y + h^2 J d + h^2 f_ext   (+ h^2 w q per penalty pin)
// solved on the free vertices (exact pins held at their targets); v_{n+1} = (x_{n+1} - x_n)/h.
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "model_io.h"

namespace {

using namespace clothsim_port;

const char* USAGE =
    "usage: clothsim_port MODEL_DIR OUT_DIR [options]\n"
    "\n"
    "Runs the local/global method on the model folder `clothsim export` writes (vertices.txt\n"
    "or x0.txt, springs.txt, masses.txt, pins.txt, forces.txt, settings.txt; optional v0.txt\n"
    "initial velocities, else 0) and writes OUT_DIR/positions.txt and velocities.txt.\n"
    "A fixed number of iterations per step (settings.txt's tolerance is not used).\n"
    "\n"
    "options:\n"
    "  --precision float|double  arithmetic of the whole run (default double)\n"
    "  --start y|x_n             initial guess of each step (default: settings initial_guess)\n"
    "  --iterations K            local/global iterations per step (default: settings)\n"
    "  --frames F                steps to take (default: settings frames)\n"
    "  --h H                     time step [s] (default: settings h)\n"
    "  --pins model|off          pins as pins.txt says (default), or no pins at all\n"
    "  --pin-stiffness W         every pin becomes a penalty pin of stiffness W [N/m]\n"
    "  --fault none|unnormalized|sign\n"
    "                            inject a bug: unnormalized local step d = r (x_a - x_b),\n"
    "                            or the spring term's sign flipped in the right-hand side\n"
    "  --help                    this text\n"
    "exit status: 0 done, 2 bad arguments or an unreadable model file\n";

struct Options {
    std::string model, out, precision = "double", start, pins = "model", fault = "none";
    int iterations = -1, frames = -1;
    double h = -1, pin_stiffness = -1;
};

[[noreturn]] void usage_error(const std::string& what) {
    std::cerr << "clothsim_port: " << what << " (see --help)\n";
    std::exit(2);
}

double parse_number(const std::string& flag, const char* text) {
    char* end = nullptr;
    double v = std::strtod(text, &end);
    if (end == text || *end != '\0' || !std::isfinite(v))
        usage_error(flag + ": not a number: '" + text + "'");
    return v;
}

int parse_count(const std::string& flag, const char* text, int lo) {
    double v = parse_number(flag, text);
    if (v != std::floor(v) || v < lo || v > 1e7)
        usage_error(flag + ": must be an integer >= " + std::to_string(lo) + ", got '" + text + "'");
    return static_cast<int>(v);
}

Options parse(int argc, char** argv) {
    Options o;
    std::vector<std::string> positional;
    for (int i = 1; i < argc; ++i) {
        std::string a = argv[i];
        if (a == "--help" || a == "-h") {
            std::cout << USAGE;
            std::exit(0);
        }
        if (a.rfind("--", 0) != 0) {
            positional.push_back(a);
            continue;
        }
        if (i + 1 >= argc) usage_error(a + ": needs a value");
        const char* v = argv[++i];
        std::string s = v;
        if (a == "--precision") {
            if (s != "float" && s != "double") usage_error("--precision: float or double, got '" + s + "'");
            o.precision = s;
        } else if (a == "--start") {
            if (s != "y" && s != "x_n") usage_error("--start: y or x_n, got '" + s + "'");
            o.start = s;
        } else if (a == "--iterations") {
            o.iterations = parse_count(a, v, 1);
        } else if (a == "--frames") {
            o.frames = parse_count(a, v, 0);
        } else if (a == "--h") {
            o.h = parse_number(a, v);
            if (!(o.h > 0)) usage_error("--h: must be > 0 s");
        } else if (a == "--pins") {
            if (s != "model" && s != "off") usage_error("--pins: model or off, got '" + s + "'");
            o.pins = s;
        } else if (a == "--pin-stiffness") {
            o.pin_stiffness = parse_number(a, v);
            if (!(o.pin_stiffness > 0)) usage_error("--pin-stiffness: must be > 0 N/m");
        } else if (a == "--fault") {
            if (s != "none" && s != "unnormalized" && s != "sign")
                usage_error("--fault: none, unnormalized or sign, got '" + s + "'");
            o.fault = s;
        } else {
            usage_error("unknown option " + a);
        }
    }
    if (positional.size() != 2) usage_error("expected MODEL_DIR and OUT_DIR");
    o.model = positional[0];
    o.out = positional[1];
    return o;
}

struct Settings {
    double h;
    int iterations, frames;
    bool start_y;
};

// One run of the method in scalar type T (float or double): every matrix, factor, local step
// and state is T; the model's double values are rounded to T once.
template <typename T>
class Port {
    using Mat = Eigen::Matrix<T, Eigen::Dynamic, 3>;
    using Sparse = Eigen::SparseMatrix<T>;

public:
    Port(const Model& m, const Options& o, const Settings& s) : m_(m), o_(o), s_(s) {
        const int n = m.n;
        std::vector<char> fixed(n, 0);
        std::vector<Pin> pins = o.pins == "off" ? std::vector<Pin>{} : m.pins;
        for (Pin& p : pins) {
            if (o.pin_stiffness > 0) {
                p.method = 1;
                p.stiffness = o.pin_stiffness;
            }
            if (p.method == 0) fixed[p.vertex] = 1;
        }
        for (int i = 0; i < n; ++i) (fixed[i] ? fixed_ : free_).push_back(i);
        std::vector<int> slot(n);
        for (size_t j = 0; j < free_.size(); ++j) slot[free_[j]] = static_cast<int>(j);
        for (size_t j = 0; j < fixed_.size(); ++j) slot[fixed_[j]] = static_cast<int>(j);

        const T h2 = T(s.h) * T(s.h);
        // c = M y + h^2 f_ext + h^2 w q: the part of the right-hand side without d
        mass_ = m.mass.cast<T>();
        base_ = h2 * m.force.cast<T>();
        target_ = Mat::Zero(n, 3);
        std::vector<Eigen::Triplet<T>> ff, fp;
        auto add = [&](int i, int j, T v) {
            if (fixed[i]) return;
            if (fixed[j]) fp.emplace_back(slot[i], slot[j], v);
            else ff.emplace_back(slot[i], slot[j], v);
        };
        for (int i = 0; i < n; ++i) add(i, i, mass_[i]);
        for (size_t e = 0; e < m.a.size(); ++e) {
            T w = h2 * T(m.k[e]);
            add(m.a[e], m.a[e], w);
            add(m.b[e], m.b[e], w);
            add(m.a[e], m.b[e], -w);
            add(m.b[e], m.a[e], -w);
        }
        for (const Pin& p : pins) {
            Eigen::Matrix<T, 1, 3> q(T(p.x), T(p.y), T(p.z));
            target_.row(p.vertex) = q;
            if (p.method == 1) {
                add(p.vertex, p.vertex, h2 * T(p.stiffness));
                base_.row(p.vertex) += h2 * (T(p.stiffness) * q);
            }
        }
        A_ff_.resize(free_.size(), free_.size());
        A_ff_.setFromTriplets(ff.begin(), ff.end());
        A_fp_.resize(free_.size(), fixed_.size());
        A_fp_.setFromTriplets(fp.begin(), fp.end());
        solver_.compute(A_ff_);
        if (solver_.info() != Eigen::Success)
            throw ReadError(m.dir + ":0: M + h^2 L cannot be factored (a free vertex of mass 0 "
                                    "without springs?)");
        d_ = Mat::Zero(m.a.size(), 3);
    }

    void run(TrajectoryWriter& out) {
        Mat x = m_.V.cast<T>(), v = m_.V0.cast<T>();
        out.frame(x, v);
        for (int f = 0; f < s_.frames; ++f) {
            Mat x_new = step(x, v);
            v = (x_new - x) / T(s_.h);
            x = x_new;
            out.frame(x, v);
        }
    }

private:
    Mat step(const Mat& x_n, const Mat& v_n) {
        const int n = m_.n;
        const T h = T(s_.h), h2 = h * h;
        Mat y = x_n + h * v_n;
        Mat c = base_;
        for (int i = 0; i < n; ++i) c.row(i) += mass_[i] * y.row(i);
        Mat x = s_.start_y ? y : x_n;
        Mat x_p(fixed_.size(), 3);
        for (size_t j = 0; j < fixed_.size(); ++j) x_p.row(j) = x.row(fixed_[j]) = target_.row(fixed_[j]);
        Mat c_f(free_.size(), 3);
        for (size_t j = 0; j < free_.size(); ++j) c_f.row(j) = c.row(free_[j]);
        if (!fixed_.empty()) c_f -= A_fp_ * x_p;
        const T sign = o_.fault == "sign" ? T(-1) : T(1);
        const bool unnormalized = o_.fault == "unnormalized";
        Mat jd(n, 3), rhs(free_.size(), 3);
        for (int it = 0; it < s_.iterations; ++it) {
            jd.setZero();
            for (Eigen::Index e = 0; e < d_.rows(); ++e) {  // local step, and J d
                Eigen::Matrix<T, 1, 3> p = x.row(m_.a[e]) - x.row(m_.b[e]);
                T len = p.norm(), r = T(m_.r[e]);
                if (unnormalized) d_.row(e) = r * p;
                else if (len > 0) d_.row(e) = p * (r / len);  // coincident: previous d kept
                Eigen::Matrix<T, 1, 3> kd = T(m_.k[e]) * d_.row(e);
                jd.row(m_.a[e]) += kd;
                jd.row(m_.b[e]) -= kd;
            }
            for (size_t j = 0; j < free_.size(); ++j)
                rhs.row(j) = c_f.row(j) + sign * h2 * jd.row(free_[j]);
            Mat x_f = solver_.solve(rhs);  // global step: n_free x n_free, 3 right-hand sides
            for (size_t j = 0; j < free_.size(); ++j) x.row(free_[j]) = x_f.row(j);
        }
        return x;
    }

    const Model& m_;
    const Options& o_;
    const Settings& s_;
    std::vector<int> free_, fixed_;
    Eigen::Matrix<T, Eigen::Dynamic, 1> mass_;
    Mat base_, target_, d_;
    Sparse A_ff_, A_fp_;
    Eigen::SimplicialLDLT<Sparse> solver_;
};

Settings settings_of(const Model& m, const Options& o) {
    Settings s;
    s.h = o.h > 0 ? o.h : setting(m, "h", NAN);
    if (!(s.h > 0)) fail("settings.txt", 0, "h: must be > 0 s");
    s.iterations = o.iterations > 0 ? o.iterations : static_cast<int>(setting(m, "iterations", NAN));
    if (s.iterations < 1) fail("settings.txt", 0, "iterations: must be >= 1");
    s.frames = o.frames >= 0 ? o.frames : static_cast<int>(setting(m, "frames", NAN));
    std::string start = o.start;
    if (start.empty()) {
        auto it = m.settings.find("initial_guess");
        start = it == m.settings.end() ? "y" : it->second;
        if (start != "y" && start != "x_n")
            fail("settings.txt", 0, "initial_guess: y or x_n, got '" + start + "'");
    }
    s.start_y = start == "y";
    auto method = m.settings.find("method");
    if (method != m.settings.end() && method->second != "local-global")
        std::cerr << "clothsim_port: warning: settings.txt method is '" << method->second
                  << "'; this port runs local-global\n";
    if (setting(m, "tolerance", 0) != 0)
        std::cerr << "clothsim_port: warning: settings.txt tolerance is ignored: this port "
                     "always does " << s.iterations << " iterations per step\n";
    return s;
}

}  // namespace

int main(int argc, char** argv) {
    Options o = parse(argc, argv);
    try {
        Model m = read_model(o.model);
        Settings s = settings_of(m, o);
        std::filesystem::create_directories(o.out);
        TrajectoryWriter out(o.out);
        if (o.precision == "float") Port<float>(m, o, s).run(out);
        else Port<double>(m, o, s).run(out);
    } catch (const ReadError& e) {
        std::cerr << "clothsim_port: " << e.what() << "\n";
        return 2;
    } catch (const std::exception& e) {
        std::cerr << "clothsim_port: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
