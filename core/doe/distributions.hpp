#pragma once
// The few distribution functions the analysis needs, written here (no statistics library in
// the dependency set): Student t and F through the regularised incomplete beta function
// (continued fraction, modified Lentz; Press et al., Numerical Recipes 3rd ed., sec. 6.4),
// quantiles by bisection on the distribution function. Non-integer degrees of freedom are
// allowed, as Lenth's m/3 needs them.

namespace demcal::doe {

/// I_x(a, b), the regularised incomplete beta function.
double incomplete_beta(double x, double a, double b);
/// P(T <= t) for Student's t with `df` degrees of freedom.
double student_t_cdf(double t, double df);
/// t such that P(T <= t) = p.
double student_t_quantile(double p, double df);
/// P(F > f) for the F distribution with (df1, df2) degrees of freedom.
double f_survival(double f, double df1, double df2);
/// Standard normal quantile.
double normal_quantile(double p);

}  // namespace demcal::doe
