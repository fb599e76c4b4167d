#include "sdlighting/zonal_design.h"

#include "quadrature/design_fit.h"
#include "sh/azimuthal_power.h"
#include "sdlighting/spherical_harmonics.h"
#include "util/number_string.h"

#include <glm/geometric.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <stdexcept>

namespace sd {
namespace {

// Base rules integrate polynomials in s of degree 2 kBaseNodes − 1 >= 2 kMaxDesignDegree + 7: the
// radial measures of order m carry (s(2−s))^m, so a degree-k basis needs degree 2k.
constexpr int kBaseNodes = kMaxDesignDegree + 4;

// 1 − z for a unit vector, without the cancellation near the pole where narrow lobes live.
double one_minus_z(const glm::dvec3& d) {
  return d.z > 0.0 ? (d.x * d.x + d.y * d.y) / (1.0 + d.z) : 1.0 - d.z;
}

glm::dvec3 direction_from(double s, double phi) {
  const double r = std::sqrt(std::max(s * (2.0 - s), 0.0));
  return {r * std::cos(phi), r * std::sin(phi), 1.0 - s};
}

// The moment equations in the basis q_j^(m)(s) · √2 {Re, Im}(x + i y)^m, orthonormal for the
// weight (q_j^(m) orthonormal for the radial measure of order m): the system's condition stays
// moderate however narrow the lobe.
MomentSystem orthonormal_zonal_system(const ZonalWeight& weight, int degree) {
  std::vector<Recurrence> radial(degree + 1);
  for (int m = 0; m <= degree; ++m) radial[m] = weight.radial_recurrence(m, degree - m + 1);
  MomentSystem system;
  system.size = sh_count(degree);
  system.target = Eigen::VectorXd::Zero(system.size);
  system.target(0) = std::sqrt(weight.mass());
  const double s_min = weight.support_min(), s_max = weight.support_max();
  system.project_to_support = [s_min, s_max](const glm::dvec3& d) {
    const double s = one_minus_z(d);
    if (s >= s_min && s <= s_max) return d;
    const double r = std::hypot(d.x, d.y);
    const double phi = r > 0.0 ? std::atan2(d.y, d.x) : 0.0;
    return direction_from(std::clamp(s, s_min, s_max), phi);
  };
  system.evaluate = [radial, degree](const glm::dvec3& d, double* values, double* gradients) {
    const double s = one_minus_z(d);
    thread_local std::vector<double> q, dq;
    q.resize(degree + 1);
    dq.resize(degree + 1);
    AzimuthalPower power;
    int index = 0;
    auto emit = [&](double value, double gx, double gy, double gz) {
      values[index] = value;
      if (gradients) {
        gradients[3 * index] = gx;
        gradients[3 * index + 1] = gy;
        gradients[3 * index + 2] = gz;
      }
      ++index;
    };
    for (int m = 0; m <= degree; ++m) {
      if (m > 0) power.next(d.x, d.y);
      const double re = power.re, im = power.im, re_prev = power.re_prev, im_prev = power.im_prev;
      const int count = degree - m + 1;
      orthonormal_polynomials(radial[m], count, s, q.data(), gradients ? dq.data() : nullptr);
      const double c = m == 0 ? 1.0 : std::sqrt(2.0);
      for (int j = 0; j < count; ++j) {
        const double a = c * q[j], da = gradients ? -c * dq[j] : 0.0;  // d/dz = −d/ds
        emit(a * re, a * m * re_prev, -a * m * im_prev, da * re);
        if (m > 0) emit(a * im, a * m * im_prev, a * m * re_prev, da * im);
      }
    }
  };
  return system;
}

// The mass of the weight closer to the pole than s, piecewise linear through a Gauss rule of the
// weight (each node's weight split evenly on both sides of it), and its inverse: where starts put
// their rings, and how continuation moves a node from one weight to another.
class MassProfile {
 public:
  MassProfile(const Rule1D& rule, double support_min, double support_max, double mass) {
    s_.push_back(support_min);
    c_.push_back(0.0);
    double cumulative = 0.0;
    for (size_t i = 0; i < rule.nodes.size(); ++i) {
      s_.push_back(rule.nodes[i]);
      c_.push_back(cumulative + 0.5 * rule.weights[i]);
      cumulative += rule.weights[i];
    }
    s_.push_back(support_max);
    c_.push_back(mass);
    for (double& c : c_) c /= mass;
  }

  /// The fraction u of the mass with s' < s.
  double fraction(double s) const { return interpolate(s_, c_, s); }

  /// The s at which a fraction u of the mass lies closer to the pole.
  double quantile(double u) const { return interpolate(c_, s_, u); }

 private:
  static double interpolate(const std::vector<double>& x, const std::vector<double>& y, double at) {
    if (at <= x.front()) return y.front();
    if (at >= x.back()) return y.back();
    const size_t i = std::upper_bound(x.begin(), x.end(), at) - x.begin();
    const double f = (at - x[i - 1]) / std::max(x[i] - x[i - 1], 1e-300);
    return y[i - 1] + f * (y[i] - y[i - 1]);
  }

  std::vector<double> s_, c_;  // increasing
};

MassProfile mass_profile(const ZonalWeight& weight) {
  return MassProfile(gauss_rule(weight.radial_recurrence(0, kBaseNodes), kBaseNodes), weight.support_min(),
                     weight.support_max(), weight.mass());
}

struct ProductRule {
  Rule1D radial;
  bool pole_node = false;
  int size(int degree) const {
    const int rings = static_cast<int>(radial.nodes.size()) - (pole_node ? 1 : 0);
    return rings * (degree + 1) + (pole_node ? 1 : 0);
  }
};

SphericalDesign product_design(const ProductRule& rule, int degree, const std::string& method) {
  SphericalDesign design;
  design.degree = degree;
  design.method = method;
  const int azimuths = degree + 1;  // equally spaced φ integrate e^{imφ} exactly for |m| <= degree
  for (size_t i = 0; i < rule.radial.nodes.size(); ++i) {
    const double s = rule.radial.nodes[i], w = rule.radial.weights[i];
    if (rule.pole_node && s == 0.0) {
      design.nodes.push_back({0.0, 0.0, 1.0});
      design.weights.push_back(w);
      continue;
    }
    for (int j = 0; j < azimuths; ++j) {
      design.nodes.push_back(direction_from(s, 2.0 * M_PI * j / azimuths));
      design.weights.push_back(w / azimuths);
    }
  }
  return design;
}

class ZonalDesignBuilder {
 public:
  ZonalDesignBuilder(const ZonalWeight& weight, int degree)
      : weight_(weight),
        degree_(degree),
        moments_(weight.sh_moments(degree)),
        profile_(mass_profile(weight)) {}

  // Gauss product rule, or its Radau variant with the pole as a node, whichever is smaller.
  SphericalDesign gauss() const {
    const int n_gauss = (degree_ + 2) / 2;  // exact for degree 2n − 1 >= degree
    ProductRule plain{gauss_rule(weight_.radial_recurrence(0, n_gauss), n_gauss), false};
    std::optional<ProductRule> radau;
    if (weight_.support_min() == 0.0) {  // the pole is an end of the support
      const int n_radau = (degree_ + 3) / 2;  // exact for degree 2n − 2 >= degree
      radau = ProductRule{gauss_radau_rule(weight_.radial_recurrence(0, n_radau), n_radau, 0.0), true};
    }
    const bool use_radau = radau && radau->size(degree_) < plain.size(degree_);
    SphericalDesign design = use_radau ? product_design(*radau, degree_, "gauss-radau")
                                       : product_design(plain, degree_, "gauss");
    certify(design);
    return design;
  }

  // Gradient projection (eq. 14): the Gauss rule thinned node by node (the seed's start), and
  // well-spread starts searched down from the generic node count; the smallest certified design.
  SphericalDesign gradient(const SphericalDesign& gauss) const {
    // Moment equations (k+1)², less the rotation about e3 that maps a zonal design to a design,
    // over three unknowns per node.
    const int generic = std::max(sh_count(degree_) / 3, design_lower_bound(degree_));
    const MomentSystem system = orthonormal_zonal_system(weight_, degree_);
    auto certify = [this](SphericalDesign& design) { return try_certify(design); };
    SphericalDesign best = prune_design(system, gauss, generic, certify, fit_options());
    best.method = "gradient";
    std::optional<SphericalDesign> spread;
    for (int n = std::min(generic, best.size() - 1); n >= design_lower_bound(degree_); --n) {
      std::optional<SphericalDesign> found = attempt(system, n);
      if (!found) break;
      spread = found;
      n = std::min(n, found->size());
    }
    for (int n = generic + 1; !spread && n < std::min(best.size(), generic + kExtraSizes + 1); ++n) {
      spread = attempt(system, n);
    }
    return spread && spread->size() < best.size() ? *spread : best;
  }

  // Continuation (msd-notes, Theorem 2.1's designs vary smoothly with the lobe): the design of a
  // neighbouring weight with each node moved along its meridian to the same mass fraction and
  // each weight scaled to the new mass, refitted (eq. 14), then (if `thin`) thinned node by node
  // while it certifies. None when the moved design does not refit to a certified one.
  std::optional<SphericalDesign> continued(const ZonalWeight& from_weight, const SphericalDesign& from,
                                           bool thin) const {
    const MassProfile from_profile = mass_profile(from_weight);
    SphericalDesign design;
    design.degree = degree_;
    design.method = "gradient";
    for (int i = 0; i < from.size(); ++i) {
      const glm::dvec3& x = from.nodes[i];
      const double phi = std::atan2(x.y, x.x);
      design.nodes.push_back(direction_from(profile_.quantile(from_profile.fraction(one_minus_z(x))), phi));
      design.weights.push_back(from.weights[i] * weight_.mass() / from_weight.mass());
    }
    const MomentSystem system = orthonormal_zonal_system(weight_, degree_);
    fit_design(system, design.nodes, design.weights, fit_options());
    if (!try_certify(design)) return std::nullopt;
    if (!thin) return design;
    auto certify = [this](SphericalDesign& candidate) { return try_certify(candidate); };
    FitOptions thinning = fit_options();
    thinning.stop_when_stalled = true;  // a node too few shows as a fit that stops converging
    for (int size = design.size(); size > design_lower_bound(degree_); size = design.size()) {
      design = prune_design(system, design, size - 1, certify, thinning);
      if (design.size() == size) break;
    }
    return design;
  }

 private:
  static constexpr int kRestarts = 4;
  // Sizes above the generic count worth trying from spread starts: beyond, thinning the Gauss
  // rule does as well (seen on narrow lobes of degree >= 10).
  static constexpr int kExtraSizes = 3;
  static constexpr int kMaxIterations = 300;

  FitOptions fit_options() const {
    FitOptions options;
    options.tolerance = 1e-15 * std::sqrt(weight_.mass());
    options.max_iterations = kMaxIterations;
    return options;
  }

  std::optional<SphericalDesign> attempt(const MomentSystem& system, int n) const {
    std::mt19937_64 rng(1000003ull * degree_ + n);
    std::uniform_real_distribution<double> jitter(-0.5, 0.5);
    for (int restart = 0; restart < kRestarts; ++restart) {
      SphericalDesign design;
      design.degree = degree_;
      design.method = "gradient";
      const double golden_angle = M_PI * (3.0 - std::sqrt(5.0));
      const double phase = 2.0 * M_PI * (jitter(rng) + 0.5);
      for (int i = 0; i < n; ++i) {
        const double u = (i + 0.5 + (restart > 0 ? 0.9 * jitter(rng) : 0.0)) / n;
        design.nodes.push_back(direction_from(profile_.quantile(u), phase + golden_angle * i));
        design.weights.push_back(weight_.mass() / n);
      }
      fit_design(system, design.nodes, design.weights, fit_options());
      if (design.size() > 0 && design.size() <= n && try_certify(design)) return design;
    }
    return std::nullopt;
  }

  bool try_certify(SphericalDesign& design) const { return certify_design(design, moments_, weight_.mass()); }

  void certify(SphericalDesign& design) const {
    if (!try_certify(design)) {
      throw std::runtime_error("zonal design of degree " + std::to_string(degree_) + " by " + design.method +
                               " failed certification: residual " + number_string(design.residual));
    }
  }

  const ZonalWeight& weight_;
  int degree_;
  std::vector<double> moments_;
  MassProfile profile_;
};

}  // namespace

DesignMethod design_method_from_name(const std::string& name) {
  if (name == "auto") return DesignMethod::Auto;
  if (name == "gauss") return DesignMethod::Gauss;
  if (name == "gradient") return DesignMethod::Gradient;
  throw std::invalid_argument("unknown design method '" + name + "' (expected 'auto', 'gauss' or 'gradient')");
}

ZonalWeight ZonalWeight::from_lobe(const ZonalLobe& lobe) {
  // ½ (2σ+2) t^σ dt = (σ+1) (1−s)^σ ds on s ∈ [0, 1]: mass 1.
  const double sigma = lobe.exponent;
  Rule1D rule = gauss_rule(jacobi_recurrence_unit_interval(sigma, kBaseNodes), kBaseNodes);
  ZonalWeight weight;
  weight.nodes_ = rule.nodes;
  weight.weights_ = rule.weights;
  for (double& w : weight.weights_) w *= sigma + 1.0;
  weight.mass_ = 1.0;
  weight.support_min_ = 0.0;
  weight.support_max_ = 1.0;
  return weight;
}

ZonalWeight ZonalWeight::tabulated(const std::vector<double>& t, const std::vector<double>& w) {
  const size_t count = t.size();
  if (count < 2 || w.size() != count) {
    throw std::invalid_argument("tabulated zonal weight needs at least two (t, w) samples of equal length");
  }
  for (size_t i = 0; i < count; ++i) {
    if (!std::isfinite(t[i]) || !std::isfinite(w[i])) throw std::invalid_argument("tabulated zonal weight has NaN or infinite samples");
    if (t[i] < -1.0 || t[i] > 1.0) throw std::invalid_argument("tabulated zonal weight: t must lie in [-1, 1]");
    if (w[i] < 0.0) throw std::invalid_argument("tabulated zonal weight must be non-negative");
    if (i > 0 && !(t[i] > t[i - 1])) throw std::invalid_argument("tabulated zonal weight: t must be strictly increasing");
  }
  // Gauss–Legendre on each segment integrates (linear w) × (polynomial of degree 2 kBaseNodes − 2).
  const Rule1D segment_rule = gauss_rule(jacobi_recurrence_unit_interval(0.0, kBaseNodes), kBaseNodes);
  std::vector<double> fine_nodes, fine_weights;
  double s_min = 2.0, s_max = 0.0;
  for (size_t i = 0; i + 1 < count; ++i) {
    if (w[i] == 0.0 && w[i + 1] == 0.0) continue;
    const double length = t[i + 1] - t[i];
    for (size_t q = 0; q < segment_rule.nodes.size(); ++q) {
      const double u = segment_rule.nodes[q];
      fine_nodes.push_back(1.0 - (t[i] + u * length));
      fine_weights.push_back(0.5 * length * segment_rule.weights[q] * ((1.0 - u) * w[i] + u * w[i + 1]));
    }
    s_min = std::min(s_min, 1.0 - t[i + 1]);
    s_max = std::max(s_max, 1.0 - t[i]);
  }
  if (fine_nodes.empty()) throw std::invalid_argument("tabulated zonal weight is zero everywhere");
  // Compress to a Gauss rule of the same exactness: every later step then costs the same as a lobe's.
  const Rule1D rule = gauss_rule(discrete_recurrence(fine_nodes, fine_weights, kBaseNodes), kBaseNodes);
  ZonalWeight weight;
  weight.nodes_ = rule.nodes;
  weight.weights_ = rule.weights;
  weight.mass_ = 0.0;
  for (double v : rule.weights) weight.mass_ += v;
  weight.support_min_ = std::max(s_min, 0.0);
  weight.support_max_ = std::min(s_max, 2.0);
  return weight;
}

std::vector<double> ZonalWeight::legendre_moments(int lmax) const {
  std::vector<double> moments(lmax + 1, 0.0), p(lmax + 1);
  for (size_t i = 0; i < nodes_.size(); ++i) {
    legendre_all(lmax, 1.0 - nodes_[i], p.data());
    for (int l = 0; l <= lmax; ++l) moments[l] += weights_[i] * p[l];
  }
  return moments;
}

std::vector<double> ZonalWeight::sh_moments(int degree) const {
  const std::vector<double> legendre_moment = legendre_moments(degree);
  std::vector<double> moments(sh_count(degree), 0.0);
  for (int l = 0; l <= degree; ++l) moments[sh_index(l, 0)] = std::sqrt(2.0 * l + 1.0) * legendre_moment[l];
  return moments;
}

Recurrence ZonalWeight::radial_recurrence(int m, int n) const {
  std::vector<double> w(weights_);
  for (size_t i = 0; i < w.size(); ++i) w[i] *= std::pow(nodes_[i] * (2.0 - nodes_[i]), m);
  return discrete_recurrence(nodes_, w, n);
}

std::optional<SphericalDesign> zonal_design_continued(const ZonalWeight& weight, int degree,
                                                      const ZonalWeight& start_weight, const SphericalDesign& start,
                                                      bool thin) {
  check_order("design degree", degree, kMaxDesignDegree);
  if (start.degree != degree || start.size() == 0 || start.weights.size() != start.nodes.size()) {
    throw std::invalid_argument("zonal_design_continued needs a start design of degree " + std::to_string(degree) +
                                " with as many weights as nodes");
  }
  ZonalDesignBuilder builder(weight, degree);
  std::optional<SphericalDesign> continued = builder.continued(start_weight, start, thin);
  if (!continued) return std::nullopt;
  SphericalDesign gauss = builder.gauss();
  return continued->size() < gauss.size() ? *continued : gauss;
}

SphericalDesign zonal_design(const ZonalWeight& weight, int degree, DesignMethod method) {
  check_order("design degree", degree, kMaxDesignDegree);
  ZonalDesignBuilder builder(weight, degree);
  if (method == DesignMethod::Gauss) return builder.gauss();
  const SphericalDesign gauss = builder.gauss();
  SphericalDesign gradient = builder.gradient(gauss);
  if (method == DesignMethod::Gradient) return gradient;
  return gradient.size() < gauss.size() ? gradient : gauss;
}

}  // namespace sd
