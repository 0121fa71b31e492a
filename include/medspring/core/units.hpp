// Length units of input files. The engine works in millimetres (mm-g-ms-N, see docs/units.md).
#pragma once

#include <string>
#include <string_view>

namespace medspring {

enum class LengthUnit { Millimetre, Centimetre, Metre, Micrometre };

/// Parses "mm", "cm", "m", "um" (also "millimetre", "meter", ...); throws InvalidInput otherwise.
LengthUnit parse_length_unit(std::string_view text);
/// Millimetres per unit: mm → 1, cm → 10, m → 1000, um → 0.001.
double to_mm(LengthUnit unit);
std::string to_string(LengthUnit unit);

}  // namespace medspring
