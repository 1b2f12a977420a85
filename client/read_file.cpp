// Bounded reads of whole files and streams (read_file.h).
#include "read_file.h"

namespace rayfarm::cli {

std::string too_large(std::uintmax_t limit) {
  constexpr std::uintmax_t kMiB = std::uintmax_t{1} << 20, kGiB = std::uintmax_t{1} << 30;
  std::string amount;
  if (limit >= kGiB && limit % kGiB == 0) amount = std::to_string(limit / kGiB) + " GiB";
  else if (limit >= kMiB && limit % kMiB == 0) amount = std::to_string(limit / kMiB) + " MiB";
  else amount = std::to_string(limit) + " bytes";
  return "larger than " + amount + ", the most rayfarm reads from one input";
}

bool read_bounded(std::istream& in, const std::filesystem::path& file, std::uintmax_t limit,
                  std::string& text) {
  std::error_code ec;
  if (!file.empty() && std::filesystem::is_regular_file(file, ec)) {
    const std::uintmax_t size = std::filesystem::file_size(file, ec);
    if (!ec && text.size() + size > limit) return false;
    if (!ec && size > 0) {
      const std::size_t at = text.size();
      text.resize(at + static_cast<std::size_t>(size));
      in.read(text.data() + at, static_cast<std::streamsize>(size));
      text.resize(at + static_cast<std::size_t>(in.gcount()));
      if (!in) return true;  // end of file before the size (it shrank)
    }
  }
  char buf[65536];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    const auto n = static_cast<std::size_t>(in.gcount());
    if (text.size() + n > limit) return false;
    text.append(buf, n);
  }
  return true;
}

}  // namespace rayfarm::cli
