// Names of an enum's values, declared once next to the enum by an
// `enum_names` overload that returns the table (found by argument-dependent
// lookup):
//
//   enum class Loss { huber, mse };
//   constexpr auto enum_names(Loss) { return std::array{EnumName{Loss::huber, "huber"}, EnumName{Loss::mse, "mse"}}; }
//
// YamlFields reads such enums by name, and name_of() gives the name back for
// writing and printing. A table's rows may carry more columns (any struct
// with `value` and `name` members): the scenario registry does.
#pragma once

#include <array>  // for the tables
#include <cstddef>
#include <stdexcept>
#include <string>

namespace comorph {

template <class E>
struct EnumName {
  E value;
  const char* name;
};
template <class E>
EnumName(E, const char*) -> EnumName<E>;

template <class E>
std::string name_of(E e) {
  for (const auto& row : enum_names(E{}))
    if (row.value == e) return row.name;
  throw std::logic_error("name_of: a value outside its enum's table (" + std::to_string(static_cast<long long>(e)) +
                         ")");
}

// The value named `name`; false (out unchanged) when no value has that name.
template <class E>
bool enum_from_name(const std::string& name, E& out) {
  for (const auto& row : enum_names(E{}))
    if (name == row.name) {
      out = row.value;
      return true;
    }
  return false;
}

// True when the table lists the values 0, 1, 2, ... in order, so that a
// value's row is at its index (name_at; check with static_assert).
template <class E>
constexpr bool in_value_order() {
  int i = 0;
  for (const auto& row : enum_names(E{}))
    if (static_cast<int>(row.value) != i++) return false;
  return true;
}

// The name of `e`, without a search or a string: for tables in value order.
template <class E>
constexpr const char* name_at(E e) {
  static_assert(in_value_order<E>(), "name_at needs a table in value order");
  return enum_names(e)[static_cast<std::size_t>(e)].name;
}

// All names in table order, e.g. "huber | mse".
template <class E>
std::string enum_name_list(const std::string& separator = " | ") {
  std::string list;
  for (const auto& row : enum_names(E{})) list += (list.empty() ? "" : separator) + std::string(row.name);
  return list;
}

}  // namespace comorph
