// A scene's vessel tree from a mesh or a segmentation (scene/build.hpp OrganTreeRequest), built as
// `medspring build vessel --branches all` builds it (docs/vessels.md): the one answer of the scene loaders
// that have the builders layer (the CLI's, apps/scene_support.cpp, and Python's, python/src/bind_scene.cpp).
// Header-only: it joins the scene and builders layers, which do not depend on each other.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "medspring/builders/vessel_build.hpp"
#include "medspring/core/check.hpp"
#include "medspring/scene/build.hpp"

namespace medspring {

/// build_vessel with the request's source and settings; its notes and warnings appended to `notes`.
inline std::shared_ptr<const SmrmTree> scene_organ_tree(const OrganTreeRequest& r,
                                                        std::vector<std::string>& notes) {
  VesselBuildSettings st;
  if (!r.mesh.empty()) {
    st.source.mesh = r.mesh;
    st.source.unit = r.mesh_unit;
  } else {
    st.source.mask = r.segmentation;
    st.source.label = r.label;
  }
  st.all_branches = true;
  st.no_blend = !r.blend;
  st.blend_spacing = r.blend_spacing;
  st.smrm = r.smrm;
  VesselBuild v = build_vessel(st);
  for (const auto& n : v.summary.notes) notes.push_back(n);
  for (const auto& w : v.summary.warnings) notes.push_back("warning: " + w);
  notes.push_back(cat("rebuilt surface vs input: Hausdorff ", v.summary.hausdorff_mm, " mm, mean ",
                      v.summary.mean_distance_mm, " mm; away from the cut ends ", v.summary.away.hausdorff_mm,
                      " mm"));
  return v.tree;
}

}  // namespace medspring
