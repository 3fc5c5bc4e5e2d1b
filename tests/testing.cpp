#include "testing.h"

#include "approx/image.h"
#include "approx/kernel2d.h"
#include "core/distributed.h"
#include "core/profile.h"
#include "core/quadrature.h"
#include "realtime/sss_pass.h"

#include <zlib.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <thread>

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

extern char** environ;

namespace ssslab::testing {

namespace fs = std::filesystem;

std::string data_path(const std::string& rel) {
    return std::string(SSSLAB_TEST_DATA_DIR) + "/" + rel;
}
std::string source_path(const std::string& rel) {
    return std::string(SSSLAB_SOURCE_DIR) + "/" + rel;
}
std::string ssslab_binary() {
    return SSSLAB_BINARY;
}

TempDir::TempDir() {
    std::random_device rd;
    for (int attempt = 0; attempt < 100; ++attempt) {
        const fs::path p = fs::temp_directory_path() /
                           ("ssslab-test-" + std::to_string(rd()) + std::to_string(attempt));
        std::error_code ec;
        if (fs::create_directory(p, ec)) {
            path_ = p;
            return;
        }
    }
    throw std::runtime_error("cannot create a temporary directory");
}

TempDir::~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
}

fs::path TempDir::write(const std::string& name, const std::string& content) const {
    const fs::path p = path_ / name;
    fs::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << content;
    return p;
}

std::vector<std::string> TempDir::files() const {
    std::vector<std::string> out;
    for (const auto& e : fs::recursive_directory_iterator(path_))
        if (e.is_regular_file()) out.push_back(fs::relative(e.path(), path_).string());
    std::sort(out.begin(), out.end());
    return out;
}

namespace {
std::string shell_quote(const std::string& s) {
    std::string q = "'";
    for (char c : s) q += (c == '\'') ? std::string("'\\''") : std::string(1, c);
    return q + "'";
}
}  // namespace

std::string read_text(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

CommandResult run_ssslab(const std::vector<std::string>& args, const fs::path& cwd,
                         const std::vector<std::string>& launcher) {
    TempDir io;
    std::string cmd = "cd " + shell_quote(cwd.string()) + " && SSSLAB_PROGRESS=0 ";
    for (const auto& a : launcher) cmd += shell_quote(a) + " ";
    cmd += shell_quote(ssslab_binary());
    for (const auto& a : args) cmd += " " + shell_quote(a);
    cmd += " </dev/null >" + shell_quote((io / "out").string()) + " 2>" +
           shell_quote((io / "err").string());
    const int status = std::system(cmd.c_str());
    CommandResult r;
    if (WIFEXITED(status))
        r.exit_code = WEXITSTATUS(status);
    else if (WIFSIGNALED(status))
        r.exit_code = 128 + WTERMSIG(status);
    r.out = read_text(io / "out");
    r.err = read_text(io / "err");
    return r;
}

std::vector<std::string> mpi_launcher(int ranks) {
    if (!dist::built_with_mpi() || std::system("command -v mpirun >/dev/null 2>&1") != 0) return {};
    return {"mpirun", "--allow-run-as-root", "--oversubscribe", "--bind-to", "none",
            "-np",    std::to_string(ranks)};
}

namespace {

/// Whether process `pid` catches `sig`, from the SigCgt mask of /proc/<pid>/status; false once
/// the process has ended.
bool catches(pid_t pid, int sig) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/status");
    std::string line;
    while (std::getline(in, line))
        if (line.rfind("SigCgt:", 0) == 0) {
            const unsigned long long mask = std::stoull(line.substr(7), nullptr, 16);
            return (mask >> (sig - 1)) & 1ULL;
        }
    return false;
}

// Wait until process `pid` has a handler for `sig` installed (up to `timeout_s`); false if it
// ended or the time ran out first.
bool wait_for_handler(pid_t pid, int sig, double timeout_s = 60.0) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < until) {
        if (catches(pid, sig)) return true;
        if (::waitpid(pid, nullptr, WNOHANG) == pid) return false;  // it ended first
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return false;
}

}  // namespace

int run_and_kill(const std::vector<std::string>& args, const fs::path& cwd, int ms, int sig) {
    const std::string bin = ssslab_binary();
    std::vector<std::string> argv_s = {bin};
    argv_s.insert(argv_s.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (auto& s : argv_s) argv.push_back(s.data());
    argv.push_back(nullptr);
    const fs::path here = fs::current_path();
    fs::current_path(cwd);
    pid_t pid = 0;
    const int rc = posix_spawn(&pid, bin.c_str(), nullptr, nullptr, argv.data(), environ);
    fs::current_path(here);
    if (rc != 0) return -1;
    // A signal the program catches is sent `ms` after its handler is in place: before that the
    // default action would kill it, and a loaded machine may take longer than `ms` to load the
    // shared libraries and parse the inputs (CI once did).
    if (sig != SIGKILL && !wait_for_handler(pid, sig)) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, nullptr, 0);
        return -2;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(ms));
    ::kill(pid, sig);
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

const char* const kSmallExperiment = R"(
[experiment]
name = "small"
title = "A small experiment"
description = "Skin1 and a custom medium."
seed = 7

[materials]
presets = ["Skin1"]

[[materials.custom]]
name = "Slab"
sigma_a_per_mm = [0.1, 0.2, 0.3]
sigma_s_per_mm = [5.0, 6.0, 7.0]
g = 0.5
eta = 1.4

[mcml]
photons = 20000
quick_factor = 0.1

[outputs.profiles]
)";

bool have_chromium() {
    return std::system("command -v chromium >/dev/null 2>&1") == 0;
}

int chromium(const std::string& what, const fs::path& page, const fs::path& dir,
             const std::string& size, const std::string& to) {
    const std::string flags =
        "--headless=new --no-sandbox --disable-gpu --disable-quic --no-first-run "
        "--disable-background-networking --disable-component-update --disable-sync "
        "--hide-scrollbars --virtual-time-budget=10000 --enable-logging=stderr --v=0 "
        "--user-data-dir=" +
        shell_quote((dir / "chromium-profile").string());
    const int status =
        std::system(("chromium " + flags + " --window-size=" + size + " " + what + " " +
                     shell_quote("file://" + page.string()) + " >" + shell_quote(to) + " 2>>" +
                     shell_quote((dir / "chromium.log").string()))
                        .c_str());
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : -1;
}

std::string ball_scene(double fov_y_deg, int width, int height) {
    char fov[32];
    std::snprintf(fov, sizeof fov, "%g", fov_y_deg);
    return R"(
[scene]
name = "ball"
[camera]
position = [0, 8, 40]
target = [0, 4, 0]
fov_y_deg = )" +
           std::string(fov) + "\nwidth = " + std::to_string(width) +
           "\nheight = " + std::to_string(height) + R"(
[[lights]]
type = "sphere"
position = [20, 40, 20]
radius = 3
radiance = [40, 40, 40]
[[lights]]
type = "environment"
radiance = [0.05, 0.05, 0.05]
[[materials]]
name = "jelly"
preset = "Skin1"
roughness = 0.3
[[materials]]
name = "floor"
type = "diffuse"
albedo = [0.5, 0.5, 0.5]
[[shapes]]
type = "sphere"
radius = 4
subdivisions = 4
translate = [0, 4.1, 0]
material = "jelly"
[[shapes]]
type = "plane"
size_x = 100
size_z = 100
material = "floor"
)";
}

RadialProfile analytic_profile(double dr_mm, int nr, double scale) {
    RadialProfile p;
    p.name = "analytic";
    p.dr_cm = dr_mm / 10.0;
    p.nr = nr;
    const double l1[3] = {0.15, 0.08, 0.05}, l2[3] = {0.8, 0.4, 0.25};  // mm
    for (int c = 0; c < 3; ++c) {
        p.rd_per_cm2[c].resize(static_cast<size_t>(nr));
        p.se_per_cm2[c].assign(static_cast<size_t>(nr), 0.0);
        for (int k = 0; k < nr; ++k) {
            const double r = (k + 0.5) * dr_mm / scale;
            p.rd_per_cm2[c][static_cast<size_t>(k)] =
                100.0 * (0.05 * std::exp(-r / l1[c]) / r + 0.5 * std::exp(-r / l2[c]) / l2[c]);
        }
        p.rd_total[c] = 0.5;
    }
    return p;
}

std::vector<approx::Kernel2D> skin_kernels() {
    const RadialProfile p = analytic_profile(0.01, 150, 0.5);
    std::vector<approx::Kernel2D> k;
    for (int c = 0; c < 3; ++c) k.emplace_back(p, c, approx::KernelGrid::from_profile(p));
    return k;
}

realtime::SssParams sss_camera(int w, int h, realtime::SssEdgeMode mode) {
    realtime::SssParams p;
    p.tan_half = 0.5;
    p.aspect = static_cast<double>(w) / h;
    p.unit_mm = 0.05;
    p.mode = mode;
    return p;
}

double pixel_mm(const realtime::SssParams& p, int h, double z) {
    return 2 * p.tan_half * z * p.unit_mm / h;
}

realtime::SssGBuffer flat_gbuffer(const approx::ImageRGB& e, double z) {
    realtime::SssGBuffer g(e.width, e.height);
    for (size_t i = 0; i < g.pixels(); ++i) {
        for (int ch = 0; ch < 3; ++ch) g.irradiance[3 * i + ch] = static_cast<float>(e.c[ch][i]);
        g.view_z[i] = static_cast<float>(z);
    }
    return g;
}

approx::ImageRGB random_image(int w, int h, double pixel_mm, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    approx::ImageRGB img(w, h, pixel_mm);
    for (auto& ch : img.c)
        for (double& v : ch) v = static_cast<float>(u(rng));  // representable in the G-buffer
    return img;
}

double rel_diff(const std::vector<float>& out, const approx::ImageRGB& ref) {
    double m = 0, r = 0;
    const size_t n = ref.c[0].size();
    for (size_t i = 0; i < n; ++i)
        for (int ch = 0; ch < 3; ++ch) {
            m = std::max(m, std::fabs(out[3 * i + ch] - ref.c[ch][i]));
            r = std::max(r, std::fabs(ref.c[ch][i]));
        }
    return m / r;
}

double rel_diff(const std::vector<float>& a, const std::vector<float>& b) {
    double m = 0, r = 0;
    for (size_t i = 0; i < a.size(); ++i) {
        m = std::max(m, std::fabs(static_cast<double>(a[i]) - b[i]));
        r = std::max(r, std::fabs(static_cast<double>(b[i])));
    }
    return m / r;
}

const std::array<realtime::SssEdgeMode, 3> kSssEdgeModes = {realtime::SssEdgeMode::kNone,
                                                            realtime::SssEdgeMode::kFollowSurface,
                                                            realtime::SssEdgeMode::kReject};

const char* edge_mode_name(realtime::SssEdgeMode m) {
    return m == realtime::SssEdgeMode::kNone     ? "none"
           : m == realtime::SssEdgeMode::kReject ? "reject"
                                                 : "follow";
}

std::string gunzip_file(const std::string& path) {
    gzFile f = gzopen(path.c_str(), "rb");
    if (!f) throw std::runtime_error("cannot open " + path);
    std::string out;
    char buf[1 << 16];
    int n;
    while ((n = gzread(f, buf, sizeof buf)) > 0) out.append(buf, static_cast<size_t>(n));
    gzclose(f);
    return out;
}

std::string lines_from(const std::string& text, int first) {
    size_t pos = 0;
    for (int line = 1; line < first && pos != std::string::npos; ++line) {
        pos = text.find('\n', pos);
        if (pos != std::string::npos) ++pos;
    }
    return pos == std::string::npos ? std::string() : text.substr(pos);
}

RgbImage read_png(const std::filesystem::path& path) {
    const std::string f = read_text(path);
    auto be32 = [&](size_t at) {
        return static_cast<uint32_t>(static_cast<unsigned char>(f[at])) << 24 |
               static_cast<uint32_t>(static_cast<unsigned char>(f[at + 1])) << 16 |
               static_cast<uint32_t>(static_cast<unsigned char>(f[at + 2])) << 8 |
               static_cast<uint32_t>(static_cast<unsigned char>(f[at + 3]));
    };
    if (f.size() < 33 || f.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0)
        throw std::runtime_error(path.string() + ": not a PNG file");
    RgbImage img;
    int channels = 0;
    std::string idat;
    for (size_t at = 8; at + 12 <= f.size();) {
        const size_t len = be32(at);
        const std::string type = f.substr(at + 4, 4);
        if (at + 12 + len > f.size())
            throw std::runtime_error(path.string() + ": chunk " + type + " runs past the end");
        const std::string body = f.substr(at + 4, 4 + len);  // type and data
        if (be32(at + 8 + len) !=
            crc32(0L, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size())))
            throw std::runtime_error(path.string() + ": bad CRC of chunk " + type);
        if (type == "IHDR") {
            img.width = static_cast<int>(be32(at + 8));
            img.height = static_cast<int>(be32(at + 12));
            const int depth = f[at + 16], colour = f[at + 17], interlace = f[at + 20];
            channels = colour == 0 ? 1 : colour == 2 ? 3 : colour == 6 ? 4 : 0;
            if (depth != 8 || channels == 0 || interlace != 0)
                throw std::runtime_error(path.string() + ": unsupported PNG format");
        } else if (type == "IDAT") {
            idat += f.substr(at + 8, len);
        }
        at += 12 + len;
    }
    const size_t stride = static_cast<size_t>(img.width) * static_cast<size_t>(channels);
    std::vector<unsigned char> raw((stride + 1) * static_cast<size_t>(img.height));
    uLongf raw_len = raw.size();
    if (uncompress(raw.data(), &raw_len, reinterpret_cast<const Bytef*>(idat.data()),
                   idat.size()) != Z_OK ||
        raw_len != raw.size())
        throw std::runtime_error(path.string() + ": corrupt PNG data");
    // Undo the per-row filters (PNG spec, section 9).
    std::vector<unsigned char> px(stride * static_cast<size_t>(img.height));
    const size_t bpp = static_cast<size_t>(channels);
    for (size_t y = 0; y < static_cast<size_t>(img.height); ++y) {
        const unsigned char filter = raw[y * (stride + 1)];
        const unsigned char* in = &raw[y * (stride + 1) + 1];
        unsigned char* out = &px[y * stride];
        const unsigned char* up = y > 0 ? &px[(y - 1) * stride] : nullptr;
        for (size_t i = 0; i < stride; ++i) {
            const int a = i >= bpp ? out[i - bpp] : 0, b = up ? up[i] : 0,
                      c = (up && i >= bpp) ? up[i - bpp] : 0;
            int pred = 0;
            if (filter == 1)
                pred = a;
            else if (filter == 2)
                pred = b;
            else if (filter == 3)
                pred = (a + b) / 2;
            else if (filter == 4) {
                const int p = a + b - c, pa = std::abs(p - a), pb = std::abs(p - b),
                          pc = std::abs(p - c);
                pred = (pa <= pb && pa <= pc) ? a : pb <= pc ? b : c;
            }
            out[i] = static_cast<unsigned char>(in[i] + pred);
        }
    }
    img.rgb.resize(3 * static_cast<size_t>(img.width) * static_cast<size_t>(img.height));
    for (size_t k = 0; k < static_cast<size_t>(img.width) * static_cast<size_t>(img.height); ++k)
        for (size_t ch = 0; ch < 3; ++ch)
            img.rgb[3 * k + ch] = px[k * bpp + (channels == 1 ? 0 : ch)];
    return img;
}

double test_scale() {
    if (const char* s = std::getenv("SSSLAB_TEST_SCALE")) return std::max(1e-3, std::atof(s));
    return 1.0;
}

double student_t_quantile(double p, double dof) {
    const double z = normal_quantile(p), z2 = z * z, n = dof;
    const double g1 = (z2 + 1) * z / 4;
    const double g2 = ((5 * z2 + 16) * z2 + 3) * z / 96;
    const double g3 = (((3 * z2 + 19) * z2 + 17) * z2 - 15) * z / 384;
    const double g4 = ((((79 * z2 + 776) * z2 + 1482) * z2 - 1920) * z2 - 945) * z / 92160;
    return z + g1 / n + g2 / (n * n) + g3 / (n * n * n) + g4 / (n * n * n * n);
}

double chi2_critical(double dof, double alpha) {
    const double z = normal_quantile(1.0 - alpha);
    const double a = 2.0 / (9.0 * dof);
    const double t = 1.0 - a + z * std::sqrt(a);
    return dof * t * t * t;
}

double chi2_statistic(const std::vector<double>& observed, const std::vector<double>& expected,
                      int& dof) {
    double chi2 = 0, o = 0, e = 0;
    int cells = 0;
    for (size_t i = 0; i < observed.size(); ++i) {
        o += observed[i];
        e += expected[i];
        if (e >= 5.0) {
            chi2 += (o - e) * (o - e) / e;
            ++cells;
            o = e = 0;
        }
    }
    if (e > 0) {  // leftover: pool into a last cell
        chi2 += (o - e) * (o - e) / e;
        ++cells;
    }
    dof = cells - 1;
    return chi2;
}

double chandrasekhar_h(double a, double mu) {
    // 400 Gauss-Legendre nodes mapped to [0, 1].
    static thread_local std::vector<double> x, w;
    if (x.empty()) {
        gauss_legendre(400, x, w);
        for (size_t i = 0; i < x.size(); ++i) {
            x[i] = 0.5 * (1 + x[i]);
            w[i] *= 0.5;
        }
    }
    const size_t n = x.size();
    std::vector<double> h(n, 1.0), next(n);
    auto integral = [&](double m, const std::vector<double>& hv) {
        double s = 0;
        for (size_t j = 0; j < n; ++j) s += w[j] * x[j] * hv[j] / (m + x[j]);
        return s;
    };
    const double root = std::sqrt(1.0 - a);
    for (int it = 0; it < 100000; ++it) {
        double change = 0;
        for (size_t i = 0; i < n; ++i) {
            next[i] = 1.0 / (root + 0.5 * a * integral(x[i], h));
            change = std::max(change, std::fabs(next[i] - h[i]));
        }
        h.swap(next);
        if (change < 1e-14) break;
    }
    return 1.0 / (root + 0.5 * a * integral(mu, h));
}

}  // namespace ssslab::testing
