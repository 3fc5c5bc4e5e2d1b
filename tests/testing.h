// Helpers shared by the tests: paths, temporary directories, the error a bad input raises,
// running the `ssslab` binary and headless Chromium, reading gzipped reference data, the
// statistics the tests compare with, the real-time tests' scene and the screen-space SSS tests'
// inputs.
#pragma once

#include "core/error.h"
#include "core/stats.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ssslab {
struct RadialProfile;  // core/profile.h
namespace approx {
class Kernel2D;   // approx/kernel2d.h
struct ImageRGB;  // approx/image.h
}  // namespace approx
namespace realtime {  // realtime/sss_pass.h
struct SssGBuffer;
struct SssParams;
enum class SssEdgeMode;
}  // namespace realtime
}  // namespace ssslab

namespace ssslab::testing {

/// The InputError that `f()` throws; if it throws none, a test failure saying `accepted` and
/// what (`what`: the input, or its name) and an empty error.
template <class F>
InputError input_error_of(F&& f, const std::string& what) {
    try {
        f();
    } catch (const InputError& e) {
        return e;
    }
    ADD_FAILURE() << "accepted:\n" << what;
    return InputError({}, "", "");
}

/// A chi-square tally of z-scores: the sum of their squares, the largest |z| and their count.
struct ZTally {
    double chi2 = 0, max_abs = 0;
    int n = 0;
    void add(double z) {
        chi2 += z * z;
        max_abs = std::max(max_abs, std::fabs(z));
        ++n;
    }
    /// The z of two independent estimates a +- sa and b +- sb; left out where either standard
    /// error is 0 or above `max_rel_se` of its estimate (too few events for Gaussian noise).
    void add_pair(double a, double sa, double b, double sb, double max_rel_se = 0.3) {
        if (!(sa > 0 && sb > 0) || sa > max_rel_se * a || sb > max_rel_se * b) return;
        add((a - b) / std::hypot(sa, sb));
    }
};

/// tests/data/<rel>
std::string data_path(const std::string& rel);
/// <source tree>/<rel>
std::string source_path(const std::string& rel);
/// Path of the built `ssslab` executable.
std::string ssslab_binary();

/// A fresh directory under the system temp dir, removed with its content on destruction.
class TempDir {
  public:
    TempDir();
    ~TempDir();
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
    const std::filesystem::path& path() const { return path_; }
    std::filesystem::path operator/(const std::string& name) const { return path_ / name; }
    /// Write a file inside the directory; returns its path.
    std::filesystem::path write(const std::string& name, const std::string& content) const;
    /// Names of the regular files in the directory, sorted.
    std::vector<std::string> files() const;

  private:
    std::filesystem::path path_;
};

struct CommandResult {
    int exit_code = -1;  ///< exit status, or 128 + signal
    std::string out, err;
};

/// Run `ssslab` with the given arguments in `cwd` (stdin from /dev/null, progress off).
CommandResult run_ssslab(const std::vector<std::string>& args, const std::filesystem::path& cwd,
                         const std::vector<std::string>& launcher = {});
/// `mpirun` for `ranks` ranks (as root too, oversubscribing the cores), or empty when this
/// build has no MPI or mpirun is not installed: the launcher for run_ssslab.
std::vector<std::string> mpi_launcher(int ranks);

/// Start `ssslab` with the given arguments in `cwd` (output to this process's), send it `sig`
/// `ms` milliseconds after it installed its handler for `sig` (after it started, for SIGKILL),
/// and return its exit status (128 + signal if it died of one; -1 if it could not start; -2 if
/// it never installed the handler).
int run_and_kill(const std::vector<std::string>& args, const std::filesystem::path& cwd, int ms,
                 int sig);

/// A small experiment ("small", seed 7): Skin1 and a custom slab medium, MCML at 20,000 photons
/// a channel (quick_factor 0.1), the profiles output.
extern const char* const kSmallExperiment;

/// Contents of a gzip file.
std::string gunzip_file(const std::string& path);
/// Contents of a file.
std::string read_text(const std::filesystem::path& path);
/// Text from line `first` (1-based) on.
std::string lines_from(const std::string& text, int first);

/// An 8-bit image read from a PNG file (as 8-bit RGB, whatever the file's colour type).
struct RgbImage {
    int width = 0, height = 0;
    std::vector<unsigned char> rgb;  ///< row-major, 3 bytes a pixel
    const unsigned char* at(int x, int y) const {
        return &rgb[3 *
                    (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x))];
    }
};
/// Decode a non-interlaced 8-bit greyscale, RGB or RGBA PNG (screenshots of the browser tests,
/// the previews OpenImageIO writes), every chunk's CRC checked, every row filter undone;
/// throws for anything else.
RgbImage read_png(const std::filesystem::path& path);

/// Whether headless Chromium is installed (the report tests skip without it; scripts/setup.sh
/// installs it).
bool have_chromium();
/// Headless Chromium on a local page, its window `size` ("1280,2000"): `what` is "--dump-dom"
/// (the DOM after the page's scripts, written to `to`) or "--screenshot='<png>'" (shell text).
/// Its profile is <dir>/chromium-profile; what it logs (the page's console too) is appended to
/// <dir>/chromium.log. Returns its exit status (128 + signal if killed).
int chromium(const std::string& what, const std::filesystem::path& page,
             const std::filesystem::path& dir, const std::string& size,
             const std::string& to = "/dev/null");

/// A scene (TOML) of the real-time tests, in mm: a Skin1 medium sphere ("jelly", radius 4) on a
/// diffuse floor under a sphere light and a dim environment, seen from (0, 8, 40) with the given
/// vertical field of view and image size.
std::string ball_scene(double fov_y_deg, int width, int height);

// The screen-space SSS tests (realtime/sss_pass.h, realtime/sss_reference.h):
/// The analytic skin-like profile: 100 (0.05 exp(-r / l1) / r + 0.5 exp(-r / l2) / l2) per
/// channel (l1 = 0.15, 0.08, 0.05 mm; l2 = 0.8, 0.4, 0.25 mm), on `nr` bins of `dr_mm`, lengths
/// stretched by `scale`; R_d = 0.5 per channel.
RadialProfile analytic_profile(double dr_mm, int nr, double scale = 1.0);
/// Its kernels of extent 1.5 mm (0.01 mm cells, n = 150), the profile at half its length, one
/// per channel.
std::vector<approx::Kernel2D> skin_kernels();
/// A camera with tan_half 0.5 and unit_mm 0.05: at view depth z = h a pixel is one world unit,
/// 0.05 mm, so skin_kernels() span 30 pixels.
realtime::SssParams sss_camera(int w, int h, realtime::SssEdgeMode mode);
/// The height in mm of a pixel at view depth z.
double pixel_mm(const realtime::SssParams& p, int h, double z);
/// A flat G-buffer: the image as irradiance, every pixel at view depth z, material 0.
realtime::SssGBuffer flat_gbuffer(const approx::ImageRGB& e, double z);
/// Irradiance uniform in [0, 1) per pixel and channel (values a float holds exactly).
approx::ImageRGB random_image(int w, int h, double pixel_mm, unsigned seed);
/// max |out - ref| over max |ref|; `out` RGB interleaved as the pass writes it.
double rel_diff(const std::vector<float>& out, const approx::ImageRGB& ref);
double rel_diff(const std::vector<float>& a, const std::vector<float>& b);
/// Every edge mode, and its name for messages ("none", "follow", "reject").
extern const std::array<realtime::SssEdgeMode, 3> kSssEdgeModes;
const char* edge_mode_name(realtime::SssEdgeMode m);

/// Factor for Monte Carlo sample counts: 1 by default, SSSLAB_TEST_SCALE for the slow variants.
double test_scale();

// The standard normal quantile and Sidak's per-test significance: core/stats.h.
using ssslab::normal_quantile;
using ssslab::sidak;
/// Quantile of Student's t distribution with `dof` degrees of freedom (Cornish-Fisher expansion
/// about the normal quantile, four terms [Abramowitz & Stegun 26.7.5]; relative error below
/// 1e-3 for dof >= 20 and p up to 1 - 1e-7).
double student_t_quantile(double p, double dof);
/// Upper critical value of the chi-square distribution with `dof` degrees of freedom at
/// significance `alpha` (Wilson-Hilferty, relative error below 1e-3 for dof >= 10).
double chi2_critical(double dof, double alpha);

/// Pearson chi-square statistic of observed counts against expected counts. Cells with an
/// expectation below 5 are pooled with their neighbours first (as pbrt and Mitsuba do).
/// Returns the statistic and sets `dof` to (pooled cells - 1).
double chi2_statistic(const std::vector<double>& observed, const std::vector<double>& expected,
                      int& dof);

/// Chandrasekhar's H function for isotropic scattering with single-scattering albedo a in
/// (0, 1], at mu in [0, 1]: the solution of 1 / H(mu) = sqrt(1 - a) + (a / 2) int_0^1 mu' H(mu')
/// / (mu + mu') dmu' (Chandrasekhar 1950, Eq. V.(23)), by fixed-point iteration on 400
/// Gauss-Legendre nodes. The index-matched half-space lit at normal incidence reflects
/// 1 - H(1) sqrt(1 - a) of the beam.
double chandrasekhar_h(double a, double mu);

}  // namespace ssslab::testing
