// The reference of the scene file: schema_markdown() prints the key tables (keys.cpp) as the
// Markdown tables that docs/scene-format.md contains verbatim; schema_keys() lists every key.
#include <set>

#include "scene/keys.hpp"

namespace swmpm::scene {

using namespace detail;

namespace {

std::string markdown_default(const Key& k) {
  if (k.required) return "required";
  if (!k.default_text.empty()) return k.default_text;
  // std::string("`"), not "`" alone: GCC 12 warns (-Wrestrict, a false positive) once inlined.
  if (!k.def.is_null()) return std::string("`") + k.def.dump() + "`";
  return "—";
}

std::string markdown_type(const Key& k) {
  if (!k.type_text.empty()) return k.type_text;
  switch (k.type) {
    case Type::number: return "number";
    case Type::integer: return "integer";
    case Type::boolean: return "boolean";
    case Type::string: return "string";
    case Type::choice: return "string";
    case Type::vector: return "vector";
    case Type::object: return "object";
    case Type::objects: return "array of objects";
    case Type::choices: return "array of strings";
    case Type::custom: return "see meaning";
  }
  return "";
}

std::string markdown_allowed(const Key& k) {
  if (!k.allowed.empty()) return k.allowed;
  switch (k.type) {
    case Type::number: return range_text(k.range, false);
    case Type::integer: return range_text(k.range, true);
    case Type::boolean: return "`true`, `false`";
    case Type::choice:
    case Type::choices: {
      std::vector<std::string> v;
      for (const auto& s : k.values) v.push_back("`" + s + "`");
      return join(v);
    }
    case Type::vector: return "`dimension` numbers";
    case Type::objects: return k.nonempty ? "≥ 1 entry" : "";
    default: return "";
  }
}

}  // namespace

std::vector<std::string> schema_keys() {
  std::set<std::string> keys;
  for (const Table* t : all_tables()) {
    for (const Key& k : t->keys) keys.insert(k.name);
  }
  return {keys.begin(), keys.end()};
}

std::string schema_markdown() {
  std::string out;
  for (const Table* t : all_tables()) {
    out += "### " + t->title + "\n\nIn " + t->where + ".\n\n";
    out += "| key | type | unit | default | allowed | meaning |\n";
    out += "|---|---|---|---|---|---|\n";
    for (const Key& k : t->keys) {
      out += "| `" + k.name + "` | " + markdown_type(k) + " | " + k.unit + " | " + markdown_default(k) +
             " | " + markdown_allowed(k) + " | " + k.meaning + " |\n";
    }
    out += "\n";
  }
  return out;
}

}  // namespace swmpm::scene
