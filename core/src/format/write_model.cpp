// SceneDesc to model-file text: every entity and attribute as written, numbers in their
// shortest exact form, so parsing the output gives the same description.
#include <sstream>

#include "rayfarm/schema.h"
#include "rayfarm/writers.h"

namespace rayfarm {

std::string write_model(const SceneDesc& desc) {
  std::ostringstream out;
  bool first = true;
  for (const EntityDesc& e : desc.entities) {
    if (!first) out << '\n';
    first = false;
    out << entity_spec(e.kind).keyword;
    if (!e.name.empty()) out << ' ' << e.name;
    out << "\n{\n";
    for (const AttrDesc& a : e.attrs) {
      out << "   " << a.key;
      if (!a.word.empty()) out << ' ' << a.word;
      for (double v : a.numbers) out << ' ' << format_number(v);
      out << '\n';
    }
    out << "}\n";
  }
  return out.str();
}

}  // namespace rayfarm
