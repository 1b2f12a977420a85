// The names of an enum's values, in one place: parsing, printing, the help text ("a|b") and
// the list of accepted values in error messages ("a, b or c") all read it.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

namespace rayfarm {

template <class T, size_t N>
class EnumTable {
 public:
  using Entry = std::pair<std::string_view, T>;

  constexpr explicit EnumTable(const Entry (&entries)[N]) {
    // Joined here so the help text is a constant the option table can point at.
    for (size_t i = 0; i < N; ++i) {
      entries_[i] = entries[i];
      if (i > 0) help_[help_size_++] = '|';
      for (char c : entries[i].first) help_[help_size_++] = c;
    }
  }

  constexpr std::optional<T> parse(std::string_view name) const {
    for (const Entry& e : entries_)
      if (e.first == name) return e.second;
    return std::nullopt;
  }

  constexpr std::string_view name(T value) const {
    for (const Entry& e : entries_)
      if (e.second == value) return e.first;
    return "?";
  }

  constexpr std::string_view value_help() const { return {help_.data(), help_size_}; }

  // "phong or blinn", "a, b or c".
  std::string accepted() const {
    std::string out;
    for (size_t i = 0; i < N; ++i)
      out += std::string(i == 0 ? "" : i + 1 == N ? " or " : ", ") + std::string(entries_[i].first);
    return out;
  }

 private:
  std::array<Entry, N> entries_{};
  std::array<char, 64> help_{};  // too small for the names: a compile error, not an overflow
  size_t help_size_ = 0;
};

}  // namespace rayfarm
