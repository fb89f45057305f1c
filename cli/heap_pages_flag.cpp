// --heap-pages of `tessera solve` and `tessera launch` (launch/heap_pages.hpp decides and applies).

#include <tessera/util/input_error.hpp>

#include "commands.hpp"

namespace tessera::cli {

const char* const kHeapPagesHelp =
    "  --heap-pages auto|4k|2m   page size of the heaps of this run's processes (default auto:\n"
    "                            2 MB pages where a fresh 4 KB page costs 8 us or more, as on\n"
    "                            hosts with shadow page tables; 4 KB pages elsewhere). 2m re-runs\n"
    "                            the process with GLIBC_TUNABLES=glibc.malloc.hugetlb=1; a\n"
    "                            glibc.malloc.hugetlb of your own GLIBC_TUNABLES wins over auto\n";

std::string take_heap_pages_flag(Args& args) {
  std::string value = "auto";
  for (std::size_t k = 0; k < args.size();) {
    if (args[k] == "--heap-pages") {
      if (k + 1 >= args.size())
        throw InputError("option --heap-pages needs a value (auto, 4k, 2m)");
      value = args[k + 1];
      args.erase(args.begin() + static_cast<std::ptrdiff_t>(k),
                 args.begin() + static_cast<std::ptrdiff_t>(k + 2));
    } else if (args[k].rfind("--heap-pages=", 0) == 0) {
      value = args[k].substr(13);
      args.erase(args.begin() + static_cast<std::ptrdiff_t>(k));
    } else {
      ++k;
    }
  }
  return value;
}

}  // namespace tessera::cli
