#include "medspring/core/units.hpp"

#include <algorithm>
#include <cctype>

#include "medspring/core/check.hpp"

namespace medspring {

LengthUnit parse_length_unit(std::string_view text) {
  std::string s(text);
  std::transform(s.begin(), s.end(), s.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (s == "mm" || s == "millimetre" || s == "millimeter" || s == "millimetres" || s == "millimeters")
    return LengthUnit::Millimetre;
  if (s == "cm" || s == "centimetre" || s == "centimeter" || s == "centimetres" || s == "centimeters")
    return LengthUnit::Centimetre;
  if (s == "m" || s == "metre" || s == "meter" || s == "metres" || s == "meters") return LengthUnit::Metre;
  if (s == "um" || s == "micrometre" || s == "micrometer" || s == "micron" || s == "microns")
    return LengthUnit::Micrometre;
  throw InvalidInput(cat("unit: unknown length unit '", text, "' (expected mm, cm, m or um)"));
}

double to_mm(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::Millimetre:
      return 1.0;
    case LengthUnit::Centimetre:
      return 10.0;
    case LengthUnit::Metre:
      return 1000.0;
    case LengthUnit::Micrometre:
      return 1e-3;
  }
  return 1.0;
}

std::string to_string(LengthUnit unit) {
  switch (unit) {
    case LengthUnit::Millimetre:
      return "mm";
    case LengthUnit::Centimetre:
      return "cm";
    case LengthUnit::Metre:
      return "m";
    case LengthUnit::Micrometre:
      return "um";
  }
  return "mm";
}

}  // namespace medspring
