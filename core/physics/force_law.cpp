#include "core/physics/force_law.h"

#include <cmath>

namespace organsim::force_law {

double shear_barrier(double J) {
  const double jm = kShearElementMinJ;
  if (J >= jm) return -std::log(J);
  return -std::log(jm) - (J - jm) / jm + (J - jm) * (J - jm) / (2 * jm * jm);
}

}  // namespace organsim::force_law
