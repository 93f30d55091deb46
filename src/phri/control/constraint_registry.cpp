#include <phri/control/constraint_registry.hpp>

namespace phri {

// ---- the registry: one line per type, X(name) for the function `name##_constraint_type()` in its file.
#define PHRI_CONSTRAINT_TYPES(X) X(plane)

#define PHRI_DECLARE_CONSTRAINT_TYPE(name) const ConstraintType& name##_constraint_type();
PHRI_CONSTRAINT_TYPES(PHRI_DECLARE_CONSTRAINT_TYPE)
#undef PHRI_DECLARE_CONSTRAINT_TYPE

std::span<const ConstraintType* const> constraint_types() {
#define PHRI_LIST_CONSTRAINT_TYPE(name) &name##_constraint_type(),
  static const ConstraintType* const types[] = {PHRI_CONSTRAINT_TYPES(PHRI_LIST_CONSTRAINT_TYPE)};
#undef PHRI_LIST_CONSTRAINT_TYPE
  return types;
}
#undef PHRI_CONSTRAINT_TYPES

const ConstraintType* find_constraint_type(std::string_view name) {
  for (const ConstraintType* type : constraint_types()) {
    if (type->name == name) return type;
  }
  return nullptr;
}

void check_constraint_keys(const ConstraintSpec& spec) {
  std::vector<std::string_view> names;
  for (const ConstraintType* type : constraint_types()) names.push_back(type->name);
  const ConstraintType* type = find_constraint_type(spec.type);
  if (!type) {
    spec.fail("type", "unknown constraint type '" + spec.type + "' (known: " + join_words(names) +
                          "; the paper's safety constraints are always on and tuned under controller.qp)");
  }
  spec.check_keys("constraint", type->keys);
}

std::unique_ptr<Constraint> make_constraint(const ConstraintSpec& spec, const ConstraintBuildContext& context) {
  check_constraint_keys(spec);
  if (spec.name.empty()) spec.fail("name", "every constraint needs a name");
  return find_constraint_type(spec.type)->make(spec, context);
}

}  // namespace phri
