// Binary read/write of declared parameter structs (core/params.hpp) for the model package format:
// a count, then one record per field (nested fields as "duffing.eta"): name, type tag, value. Records
// are found by name, so a field added later reads as its default from an older file, and a file with a
// field this build does not know is refused naming it. Ranges are not checked here (the model's
// constructor does, naming the package): decoding is structural.
#pragma once

#include <cstdint>
#include <string>
#include <type_traits>
#include <vector>

#include "medspring/core/binary.hpp"
#include "medspring/core/params.hpp"

namespace medspring {

namespace params_binary_detail {

enum Tag : std::uint8_t { kNumber = 0, kInteger = 1, kBool = 2, kEnum = 3, kIndexList = 4 };

template <class F>
constexpr Tag tag_of() {
  if constexpr (std::is_same_v<F, bool>)
    return kBool;
  else if constexpr (std::is_enum_v<F>)
    return kEnum;
  else if constexpr (std::is_integral_v<F>)
    return kInteger;
  else if constexpr (std::is_arithmetic_v<F>)
    return kNumber;
  else
    return kIndexList;
}

template <ParamStruct T>
void count_fields(const T& p, std::uint32_t& n) {
  for_each_field(p, [&](const ParamSpec&, const auto& f) {
    using F = std::remove_cvref_t<decltype(f)>;
    if constexpr (ParamStruct<F>)
      count_fields(f, n);
    else
      ++n;
  });
}

template <ParamStruct T>
void put_fields(ByteWriter& w, const T& p, const std::string& prefix) {
  for_each_field(p, [&](const ParamSpec& s, const auto& f) {
    using F = std::remove_cvref_t<decltype(f)>;
    const std::string name = prefix + std::string(s.json_name());
    if constexpr (ParamStruct<F>) {
      put_fields(w, f, name + ".");
    } else {
      w.str(name, 256);
      w.u8(tag_of<F>());
      if constexpr (std::is_same_v<F, bool>)
        w.flag(f);
      else if constexpr (std::is_enum_v<F>)
        w.str(enum_text(f), 256);
      else if constexpr (std::is_integral_v<F>)
        w.i64(static_cast<std::int64_t>(f));
      else if constexpr (std::is_arithmetic_v<F>)
        w.f64(static_cast<double>(f));
      else {
        w.u64(f.size());
        for (Index i : f) w.i64(i);
      }
    }
  });
}

/// Reads the value of record `name` into the field of that name; false when no field has it.
template <ParamStruct T>
bool read_field(ByteReader& r, T& p, const std::string& prefix, const std::string& name, Tag tag) {
  bool found = false;
  for_each_field(p, [&](const ParamSpec& s, auto& f) {
    using F = std::remove_cvref_t<decltype(f)>;
    if (found) return;
    const std::string mine = prefix + std::string(s.json_name());
    if constexpr (ParamStruct<F>) {
      if (name.rfind(mine + ".", 0) == 0) found = read_field(r, f, mine + ".", name, tag);
    } else {
      if (name != mine) return;
      found = true;
      if (tag != tag_of<F>())
        r.fail(cat(name, ": stored as type ", int{tag}, ", expected ", int{tag_of<F>()}));
      if constexpr (std::is_same_v<F, bool>) {
        f = r.flag(name.c_str());
      } else if constexpr (std::is_enum_v<F>) {
        const std::string text = r.str(name.c_str(), 256);
        try {
          f = parse_enum(text, static_cast<F*>(nullptr));
        } catch (const InvalidInput& e) {
          r.fail(cat(name, ": ", e.what()));
        }
      } else if constexpr (std::is_integral_v<F>) {
        f = static_cast<F>(r.i64());
      } else if constexpr (std::is_arithmetic_v<F>) {
        f = static_cast<F>(r.f64());
      } else {
        const Index n = r.count(name.c_str(), 8);
        f.assign(static_cast<std::size_t>(n), 0);
        for (Index k = 0; k < n; ++k) f[static_cast<std::size_t>(k)] = static_cast<Index>(r.i64());
      }
    }
  });
  return found;
}

}  // namespace params_binary_detail

/// Writes every declared field of p.
template <ParamStruct T>
void put_params(ByteWriter& w, const T& p) {
  std::uint32_t n = 0;
  params_binary_detail::count_fields(p, n);
  w.u32(n);
  params_binary_detail::put_fields(w, p, "");
}

/// Reads what put_params wrote into p (fields absent from the file keep p's values). Throws (through
/// r.fail) for an unknown field, a type that does not match, a repeated field or a truncated record.
template <ParamStruct T>
void get_params(ByteReader& r, T& p, const char* what) {
  const std::uint32_t n = r.u32();
  if (n > 4096) r.fail(cat(what, ": ", n, " parameters"));
  std::vector<std::string> seen;
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::string name = r.str(what, 256);
    for (const std::string& s : seen)
      if (s == name) r.fail(cat(what, ": parameter '", name, "' twice"));
    seen.push_back(name);
    const auto tag = static_cast<params_binary_detail::Tag>(r.u8());
    if (!params_binary_detail::read_field(r, p, "", name, tag))
      r.fail(cat(what, ": unknown parameter '", name, "' (written by a newer MedSpring?)"));
  }
}

}  // namespace medspring
