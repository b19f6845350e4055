// Fidelity rtl where this build has no Verilated early-visibility unit (no Verilator; sanitizer,
// fuzz and minimal builds skip rtl_ref): the top-level CMakeLists.txt compiles this file into
// tilevis_top in place of rtl_ref's tilevis_rtl_evu, so make_rtl_evu always links.
#include <stdexcept>

#include "units/early_visibility_unit/rtl_evu.h"

namespace tilevis::sim {

std::unique_ptr<RtlEvu> make_rtl_evu(uint32_t, uint32_t, uint32_t) {
  throw std::runtime_error(
      "fidelity rtl needs the Verilated early-visibility unit: this build has none (Verilator, Debian package "
      "verilator, is not installed, or this is a sanitizer/fuzz/minimal build)");
}

bool rtl_evu_available() { return false; }

}  // namespace tilevis::sim
