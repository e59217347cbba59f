// Reading the model folder `clothsim export` writes, and writing a port's trajectory.
//
// Shared by clothsim_port.cpp and assignment_driver.cpp. Every file is plain text,
// whitespace-separated, '#' starts a comment, blank lines are skipped. A file or line that
// cannot be read throws ReadError, whose what() is one line "FILE:LINE: what is wrong".
#pragma once

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace clothsim_port {

struct ReadError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

struct Pin {
    int vertex;
    int method;        // 0 exact (held at the target), 1 penalty (spring of rest 0)
    double stiffness;  // [N/m], 0 for exact pins
    double x, y, z;    // target [m]
};

struct Model {
    int n = 0;
    Eigen::MatrixXd V;              // n x 3 initial positions [m]
    Eigen::MatrixXd V0;             // n x 3 initial velocities [m/s] (0 without v0.txt)
    std::vector<int> a, b;          // spring ends, 0-based
    std::vector<double> k, r;       // stiffness [N/m], rest length [m]
    Eigen::VectorXd mass;           // n [kg]
    std::vector<Pin> pins;
    Eigen::MatrixXd force;          // n x 3 external force [N], constant
    std::map<std::string, std::string> settings;  // settings.txt: key -> value
    std::string dir;
};

// The numbers of each non-empty line of `path` (comments removed), with its line number.
struct Line {
    int number;
    std::vector<std::string> fields;
};

inline std::vector<Line> read_lines(const std::string& path, const std::string& name,
                                    bool required = true) {
    std::ifstream in(path);
    std::vector<Line> out;
    if (!in) {
        if (required) throw ReadError(name + ":0: cannot open " + path);
        return out;
    }
    std::string text;
    int number = 0;
    while (std::getline(in, text)) {
        ++number;
        auto hash = text.find('#');
        if (hash != std::string::npos) text.erase(hash);
        std::istringstream words(text);
        Line line{number, {}};
        std::string w;
        while (words >> w) line.fields.push_back(w);
        if (!line.fields.empty()) out.push_back(line);
    }
    return out;
}

[[noreturn]] inline void fail(const std::string& name, int line, const std::string& what) {
    throw ReadError(name + ":" + std::to_string(line) + ": " + what);
}

inline double number(const std::string& name, const Line& line, size_t i, const char* field) {
    const std::string& s = line.fields.at(i);
    char* end = nullptr;
    double v = std::strtod(s.c_str(), &end);
    if (end == s.c_str() || *end != '\0' || !std::isfinite(v))
        fail(name, line.number, std::string(field) + ": not a finite number: '" + s + "'");
    return v;
}

inline int index(const std::string& name, const Line& line, size_t i, const char* field,
                 int n) {
    double v = number(name, line, i, field);
    if (v != std::floor(v) || v < 0 || v >= n)
        fail(name, line.number, std::string(field) + ": vertex index must be an integer in [0, " +
                                    std::to_string(n) + "), got '" + line.fields[i] + "'");
    return static_cast<int>(v);
}

inline void expect_fields(const std::string& name, const Line& line, size_t lo, size_t hi,
                          const char* what) {
    if (line.fields.size() < lo || line.fields.size() > hi)
        fail(name, line.number, std::string("expected ") + what + ", got " +
                                    std::to_string(line.fields.size()) + " numbers");
}

// n x 3 from "n lines of x y z" or "one line of 3n numbers".
inline Eigen::MatrixXd read_vectors(const std::string& dir, const std::string& name, int n,
                                    bool required = true) {
    auto lines = read_lines(dir + "/" + name, name, required);
    if (lines.empty()) {
        if (required) fail(name, 0, "no numbers in the file");
        return Eigen::MatrixXd::Zero(n > 0 ? n : 0, 3);
    }
    std::vector<double> v;
    for (const auto& line : lines) {
        if (lines.size() > 1) expect_fields(name, line, 3, 3, "3 numbers x y z");
        for (size_t i = 0; i < line.fields.size(); ++i) v.push_back(number(name, line, i, "x y z"));
    }
    if (v.size() % 3 != 0)
        fail(name, lines[0].number, "expected 3 numbers per vertex, got " + std::to_string(v.size()));
    int count = static_cast<int>(v.size() / 3);
    if (n >= 0 && count != n)
        fail(name, lines.back().number, "expected " + std::to_string(n) + " vertices, got " +
                                            std::to_string(count));
    Eigen::MatrixXd M(count, 3);
    for (int i = 0; i < count; ++i)
        for (int c = 0; c < 3; ++c) M(i, c) = v[3 * i + c];
    return M;
}

// Reads the model folder. Throws ReadError on the first bad file or line. A damping column
// with a nonzero value is refused (this port has no damping).
inline Model read_model(const std::string& dir) {
    Model m;
    m.dir = dir;
    if (!std::filesystem::is_directory(dir))
        throw ReadError(dir + ":0: not a directory (the folder `clothsim export` writes)");
    {
        std::ifstream probe(dir + "/vertices.txt");
        m.V = probe ? read_vectors(dir, "vertices.txt", -1) : read_vectors(dir, "x0.txt", -1);
    }
    m.n = static_cast<int>(m.V.rows());
    const int n = m.n;
    for (const auto& line : read_lines(dir + "/springs.txt", "springs.txt")) {
        const std::string f = "springs.txt";
        expect_fields(f, line, 4, 5, "4 or 5 numbers: a b k r [damping]");
        int a = index(f, line, 0, "a", n), b = index(f, line, 1, "b", n);
        double k = number(f, line, 2, "k"), r = number(f, line, 3, "r");
        if (a == b) fail(f, line.number, "a spring joins vertex " + std::to_string(a) + " to itself");
        if (k < 0) fail(f, line.number, "k: stiffness must be >= 0 N/m");
        if (r < 0) fail(f, line.number, "r: rest length must be >= 0 m");
        if (line.fields.size() == 5 && number(f, line, 4, "damping") != 0)
            fail(f, line.number, "damping " + line.fields[4] +
                                     " N s/m: this port has no spring damping (export a "
                                     "scene without it)");
        m.a.push_back(a); m.b.push_back(b); m.k.push_back(k); m.r.push_back(r);
    }
    auto masses = read_lines(dir + "/masses.txt", "masses.txt");
    if (static_cast<int>(masses.size()) != n)
        fail("masses.txt", masses.empty() ? 0 : masses.back().number,
             "expected " + std::to_string(n) + " masses (one a line), got " +
                 std::to_string(masses.size()));
    m.mass.resize(n);
    for (int i = 0; i < n; ++i) {
        expect_fields("masses.txt", masses[i], 1, 1, "one mass a line");
        m.mass[i] = number("masses.txt", masses[i], 0, "mass");
        if (m.mass[i] < 0) fail("masses.txt", masses[i].number, "mass: must be >= 0 kg");
    }
    for (const auto& line : read_lines(dir + "/pins.txt", "pins.txt")) {
        const std::string f = "pins.txt";
        expect_fields(f, line, 6, 6, "6 numbers: vertex method stiffness x y z");
        Pin p{index(f, line, 0, "vertex", n), 0, 0, 0, 0, 0};
        double method = number(f, line, 1, "method");
        if (method != 0 && method != 1) fail(f, line.number, "method: must be 0 (exact) or 1 (penalty)");
        p.method = static_cast<int>(method);
        p.stiffness = number(f, line, 2, "stiffness");
        if (p.method == 1 && !(p.stiffness > 0))
            fail(f, line.number, "stiffness: a penalty pin needs a stiffness > 0 N/m");
        p.x = number(f, line, 3, "x"); p.y = number(f, line, 4, "y"); p.z = number(f, line, 5, "z");
        m.pins.push_back(p);
    }
    m.force = read_vectors(dir, "forces.txt", n);
    m.V0 = read_vectors(dir, "v0.txt", n, false);
    for (const auto& line : read_lines(dir + "/settings.txt", "settings.txt")) {
        expect_fields("settings.txt", line, 2, 2, "'key value'");
        m.settings[line.fields[0]] = line.fields[1];
    }
    return m;
}

// A setting as a number; `fallback` when absent (NaN fallback: required).
inline double setting(const Model& m, const std::string& key, double fallback) {
    auto it = m.settings.find(key);
    if (it == m.settings.end()) {
        if (std::isnan(fallback)) fail("settings.txt", 0, "missing key '" + key + "'");
        return fallback;
    }
    char* end = nullptr;
    double v = std::strtod(it->second.c_str(), &end);
    if (end == it->second.c_str() || *end != '\0' || !std::isfinite(v))
        fail("settings.txt", 0, key + ": not a finite number: '" + it->second + "'");
    return v;
}

// Writes one frame (one line of 3n numbers, %.17g) to positions.txt / velocities.txt.
class TrajectoryWriter {
public:
    explicit TrajectoryWriter(const std::string& out) {
        x_ = std::fopen((out + "/positions.txt").c_str(), "w");
        v_ = std::fopen((out + "/velocities.txt").c_str(), "w");
        if (!x_ || !v_) throw ReadError(out + ":0: cannot write positions.txt / velocities.txt");
    }
    ~TrajectoryWriter() {
        if (x_) std::fclose(x_);
        if (v_) std::fclose(v_);
    }
    template <typename MatX, typename MatV>
    void frame(const MatX& x, const MatV& v) {
        line(x_, x);
        line(v_, v);
    }

private:
    template <typename Mat>
    static void line(FILE* f, const Mat& x) {
        for (Eigen::Index i = 0; i < x.rows(); ++i)
            for (int c = 0; c < 3; ++c)
                std::fprintf(f, (i || c) ? " %.17g" : "%.17g", static_cast<double>(x(i, c)));
        std::fputc('\n', f);
    }
    FILE* x_ = nullptr;
    FILE* v_ = nullptr;
};

}  // namespace clothsim_port
