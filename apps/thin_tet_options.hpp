// The thin-tetrahedron term's options of `build volumetric`, `accuracy` and `calibrate` (issue 23,
// docs/volumetric-mesh.md): --thin-tet off|scale_springs|clip and --thin-tet-q-max Q, read through the
// declaration of VolumetricSettings (models/volumetric_body.hpp: its names, defaults, ranges and help).
#pragma once

#include <string>

#include "cli.hpp"
#include "command_options.hpp"
#include "medspring/core/check.hpp"
#include "medspring/models/volumetric_body.hpp"

namespace medspring::cli {

inline OptionSpec thin_tet_option() {
  return declared_option<VolumetricSettings>("thin-tet", "thin_tet", "off|scale_springs|clip");
}
inline OptionSpec thin_tet_q_max_option() {
  return declared_option<VolumetricSettings>("thin-tet-q-max", "thin_tet_q_max", "Q");
}

/// Sets vs.thin_tet and vs.thin_tet_q_max from --thin-tet / --thin-tet-q-max (set_param: the declared
/// checks); InvalidInput "cmd: --thin-tet-q-max: thin_tet_q_max: must be in (0, 1] (got 2)" otherwise.
inline void read_thin_tet_options(const Args& args, VolumetricSettings& vs, const std::string& cmd) {
  for (const auto& [option, field] :
       {std::pair<const char*, const char*>{"thin-tet", "thin_tet"}, {"thin-tet-q-max", "thin_tet_q_max"}})
    if (const auto text = args.get(option)) {
      try {
        set_param(vs, field, *text);
      } catch (const InvalidInput& e) {
        throw InvalidInput(cat(cmd, ": --", option, ": ", e.what()));
      }
    }
}

}  // namespace medspring::cli
