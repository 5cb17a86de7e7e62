#include <algorithm>
#include <cmath>

#include "purkinje/renderer/radiometry.h"

namespace purkinje::renderer {

double fresnel_reflectance(double cos_incidence, double n1, double n2) {
  const double cos_i = std::clamp(std::abs(cos_incidence), 0.0, 1.0);
  const double sin_t2 = (n1 / n2) * (n1 / n2) * (1.0 - cos_i * cos_i);
  if (sin_t2 >= 1.0) return 1.0;  // total internal reflection
  const double cos_t = std::sqrt(1.0 - sin_t2);
  const double rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
  const double rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
  return 0.5 * (rs * rs + rp * rp);
}

double anterior_inner_index(const EyeModel& model) {
  return model.posterior_cornea ? model.posterior_cornea->cornea_index : model.aqueous_index;
}

}  // namespace purkinje::renderer
