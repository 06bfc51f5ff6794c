#include "sim/intensity.h"

#include <stdexcept>
#include <string>

namespace rmap::sim {

void IntensityModel::validate() const {
  auto require = [](bool ok, const char* what, double value) {
    if (!ok) throw std::invalid_argument(std::string("IntensityModel: ") + what + ", got " + std::to_string(value));
  };
  require(gain > 0.0 && std::isfinite(gain), "gain must be > 0", gain);
  require(range_exponent > 0.0 && std::isfinite(range_exponent), "range_exponent must be > 0", range_exponent);
  require(incidence_exponent >= 0.0 && std::isfinite(incidence_exponent), "incidence_exponent must be ≥ 0",
          incidence_exponent);
  require(near_range_m > 0.0 && std::isfinite(near_range_m), "near_range_m must be > 0", near_range_m);
  require(near_exponent > 0.0 && std::isfinite(near_exponent), "near_exponent must be > 0", near_exponent);
  require(saturation > 0.0, "saturation must be > 0", saturation);
  require(noise_rel_sigma >= 0.0 && std::isfinite(noise_rel_sigma), "noise_rel_sigma must be ≥ 0", noise_rel_sigma);
}

}  // namespace rmap::sim
