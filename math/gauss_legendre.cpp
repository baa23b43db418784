// math/gauss_legendre.cpp - Gauss-Legendre nodes and weights (paper section 6).
#include "math/gauss_legendre.h"

namespace mbr {

namespace {

/// P_n(x) and P_n'(x) by the three-term recurrence (k+1) P_{k+1} = (2k+1) x P_k - k P_{k-1}.
void legendre(int n, double x, double& p_n, double& dp_n) {
    double p0 = 1, p1 = x;
    for (int k = 1; k < n; ++k) {
        double p2 = ((2 * k + 1) * x * p1 - k * p0) / (k + 1);
        p0 = p1;
        p1 = p2;
    }
    p_n = p1;
    dp_n = n * (x * p1 - p0) / (x * x - 1);
}

}  // namespace

GaussLegendre gauss_legendre(int n) {
    MBR_CHECK_MSG(n >= 1, "n = " << n);
    GaussLegendre rule;
    rule.x.assign(n, 0.0);
    rule.w.assign(n, 0.0);
    // The roots of P_n are symmetric about 0: find the positive ones by Newton's method from
    // the asymptotic guess cos(pi (i + 3/4) / (n + 1/2)); w_i = 2 / ((1 - x_i^2) P_n'(x_i)^2).
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double x = std::cos(Pi * (i + 0.75) / (n + 0.5));
        double p, dp;
        for (int iter = 0; iter < 100; ++iter) {
            legendre(n, x, p, dp);
            double dx = p / dp;
            x -= dx;
            if (std::fabs(dx) <= 1e-15) break;
        }
        legendre(n, x, p, dp);
        double w = 2.0 / ((1 - x * x) * dp * dp);
        rule.x[i] = -x;
        rule.x[n - 1 - i] = x;
        rule.w[i] = w;
        rule.w[n - 1 - i] = w;
    }
    if (n % 2 == 1) rule.x[n / 2] = 0;  // the middle node is exactly zero
    return rule;
}

}  // namespace mbr
