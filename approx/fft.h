// FFTW for the module's exact convolutions (approx/*.cpp only; not part of the public
// interface): one global lock for planning (FFTW's planner is not thread-safe), aligned buffers,
// a 2D real transform pair, and the transform sizes FFTW handles fastest.
#pragma once

#include <fftw3.h>

#include <algorithm>
#include <cstddef>
#include <memory>
#include <mutex>
#include <new>
#include <stdexcept>

namespace ssslab::approx::detail {

inline std::mutex& fftw_mutex() {
    static std::mutex m;
    return m;
}

struct FftwFree {
    void operator()(void* p) const { fftw_free(p); }
};
using RealBuf = std::unique_ptr<double[], FftwFree>;
using ComplexBuf = std::unique_ptr<fftw_complex[], FftwFree>;

inline RealBuf alloc_real(std::size_t n) {
    auto* p = static_cast<double*>(fftw_malloc(sizeof(double) * n));
    if (!p) throw std::bad_alloc();
    return RealBuf(p);
}
inline ComplexBuf alloc_complex(std::size_t n) {
    auto* p = static_cast<fftw_complex*>(fftw_malloc(sizeof(fftw_complex) * n));
    if (!p) throw std::bad_alloc();
    return ComplexBuf(p);
}

// A 2D real transform pair of size ny x nx (row-major) on its own buffers. Planning and
// destruction hold the global FFTW lock; execution is thread-safe.
class Fft2D {
  public:
    Fft2D(int nx, int ny) {
        const std::size_t nreal = static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny);
        const std::size_t ncplx =
            static_cast<std::size_t>(nx / 2 + 1) * static_cast<std::size_t>(ny);
        real_ = alloc_real(nreal);
        spec_ = alloc_complex(ncplx);
        std::lock_guard<std::mutex> lock(fftw_mutex());
        fwd_ = fftw_plan_dft_r2c_2d(ny, nx, real_.get(), spec_.get(), FFTW_ESTIMATE);
        inv_ = fftw_plan_dft_c2r_2d(ny, nx, spec_.get(), real_.get(), FFTW_ESTIMATE);
        if (!fwd_ || !inv_) {
            if (fwd_) fftw_destroy_plan(fwd_);
            if (inv_) fftw_destroy_plan(inv_);
            throw std::runtime_error("FFTW: planning failed");
        }
    }
    ~Fft2D() {
        std::lock_guard<std::mutex> lock(fftw_mutex());
        fftw_destroy_plan(fwd_);
        fftw_destroy_plan(inv_);
    }
    Fft2D(const Fft2D&) = delete;
    Fft2D& operator=(const Fft2D&) = delete;

    double* real() { return real_.get(); }
    fftw_complex* spec() { return spec_.get(); }
    void forward() { fftw_execute(fwd_); }  // real -> spec
    void inverse() { fftw_execute(inv_); }  // spec -> real (unnormalised; destroys spec)

  private:
    RealBuf real_;
    ComplexBuf spec_;
    fftw_plan fwd_ = nullptr, inv_ = nullptr;
};

// The smallest n' >= n whose prime factors are 2, 3, 5 and 7 (sizes FFTW handles fastest).
inline int fft_size(int n) {
    for (int m = std::max(n, 1);; ++m) {
        int k = m;
        for (int f : {2, 3, 5, 7})
            while (k % f == 0) k /= f;
        if (k == 1) return m;
    }
}

}  // namespace ssslab::approx::detail
