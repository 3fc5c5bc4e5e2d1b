// Helpers shared by the tests: paths, temporary directories, running the `ssslab` binary,
// reading gzipped reference data, and the statistics the tests compare with.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace ssslab::testing {

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
CommandResult run_ssslab(const std::vector<std::string>& args, const std::filesystem::path& cwd);

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
/// Decode a non-interlaced 8-bit greyscale, RGB or RGBA PNG (screenshots of the browser tests);
/// throws for anything else.
RgbImage read_png(const std::filesystem::path& path);

/// Factor for Monte Carlo sample counts: 1 by default, SSSLAB_TEST_SCALE for the slow variants.
double test_scale();

/// Standard normal quantile (inverse CDF), to ~1e-12.
double normal_quantile(double p);
/// Upper critical value of the chi-square distribution with `dof` degrees of freedom at
/// significance `alpha` (Wilson-Hilferty, relative error below 1e-3 for dof >= 10).
double chi2_critical(double dof, double alpha);
/// Per-test significance giving family-wise `alpha` over `tests` tests (Sidak).
double sidak(double alpha, int tests);

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
