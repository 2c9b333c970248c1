#pragma once
/// \file
/// Piecewise-linear interpolation in a table of sorted abscissae: the one implementation behind input
/// profiles, friction tables, log comparison and the identification's resampling.

#include <algorithm>
#include <cstddef>

namespace jointsim {

/// What happens outside [x_0, x_{n-1}].
enum class Ends {
  Hold,         ///< the end values (y_0 left of the table, y_{n-1} right of it)
  Extrapolate,  ///< continue the first and the last segment linearly (Modelica tables)
};

/// y(at) by linear interpolation in n points (x_i, y_i), x ascending (of equal abscissae the last one counts),
/// n >= 1 (one point: a constant).
/// `x(i)` and `y(i)` return the i-th abscissa and ordinate (so any storage works: arrays, rows, columns).
/// Inside the table the segment is [x_{k-1}, x_k] with x_{k-1} <= at < x_k (at a knot: the segment to its
/// right, whose left end is exact), and y = y_{k-1} + w (y_k − y_{k-1}) with w = (at − x_{k-1}) / (x_k − x_{k-1}).
template <class X, class Y>
double interpolateLinear(std::size_t n, X x, Y y, double at, Ends ends) {
  if (n == 1) return y(0);
  std::size_t k;  // right end of the segment
  if (at < x(0)) {
    if (ends == Ends::Hold) return y(0);
    k = 1;
  } else if (at >= x(n - 1)) {
    if (ends == Ends::Hold) return y(n - 1);
    k = n - 1;
  } else {
    std::size_t lo = 0, hi = n - 1;  // invariant: x(lo) <= at < x(hi)
    while (hi - lo > 1) {
      const std::size_t mid = lo + (hi - lo) / 2;
      if (x(mid) <= at)
        lo = mid;
      else
        hi = mid;
    }
    k = hi;
  }
  const double x0 = x(k - 1), y0 = y(k - 1);
  const double w = (at - x0) / (x(k) - x0);
  return y0 + w * (y(k) - y0);
}

}  // namespace jointsim
