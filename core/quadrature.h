// Gauss-Legendre quadrature rules, shared by the engines, the models and the tests.
#pragma once

#include <vector>

namespace ssslab {

/// The n-point Gauss-Legendre rule on [-1, 1]: nodes x (increasing) and weights w, exact for
/// polynomials of degree 2n - 1. Nodes by Newton's method on P_n (three-term recurrence) from
/// Tricomi's initial guess; weights 2 / ((1 - x^2) P_n'(x)^2). n >= 1.
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w);

}  // namespace ssslab
