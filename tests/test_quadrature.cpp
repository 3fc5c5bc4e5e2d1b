// core/quadrature.h: the Gauss-Legendre rule against exact integrals of polynomials.
#include "core/quadrature.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace ssslab {
namespace {

TEST(Quadrature, GaussLegendreIsExactUpToDegree2nMinus1) {
    // int_{-1}^{1} x^k dx = 2 / (k + 1) for even k, 0 for odd k.
    for (int n : {1, 2, 3, 7, 20, 64, 400}) {
        SCOPED_TRACE(n);
        std::vector<double> x, w;
        gauss_legendre(n, x, w);
        ASSERT_EQ(x.size(), static_cast<size_t>(n));
        for (int i = 1; i < n; ++i)
            EXPECT_LT(x[static_cast<size_t>(i - 1)], x[static_cast<size_t>(i)]);
        for (int i = 0; i < n; ++i) {
            EXPECT_GT(w[static_cast<size_t>(i)], 0.0);
            EXPECT_NEAR(x[static_cast<size_t>(i)], -x[static_cast<size_t>(n - 1 - i)], 1e-15);
        }
        for (int k = 0; k <= std::min(2 * n - 1, 40); ++k) {
            double sum = 0;
            for (int i = 0; i < n; ++i)
                sum += w[static_cast<size_t>(i)] * std::pow(x[static_cast<size_t>(i)], k);
            const double exact = k % 2 ? 0.0 : 2.0 / (k + 1);
            EXPECT_NEAR(sum, exact, 1e-13) << "degree " << k;
        }
    }
    std::vector<double> x, w;
    EXPECT_THROW(gauss_legendre(0, x, w), std::invalid_argument);
}

}  // namespace
}  // namespace ssslab
