#include "medspring/geometry/volume.hpp"

namespace medspring {

MaskVolume select_label(const LabelVolume& labels, std::int32_t label) {
  MaskVolume m;
  m.dims = labels.dims;
  m.spacing = labels.spacing;
  m.origin = labels.origin;
  m.direction = labels.direction;
  m.data.resize(labels.data.size());
  for (std::size_t i = 0; i < labels.data.size(); ++i)
    m.data[i] = static_cast<std::uint8_t>(label < 0 ? labels.data[i] > 0 : labels.data[i] == label);
  return m;
}

}  // namespace medspring
