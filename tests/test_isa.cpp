// The kernels' instruction set, chosen at run time (kernels/isa.hpp): the AVX2 copy of a portable build runs the
// same scheme as the baseline code, and each copy is deterministic.
#include <catch2/catch.hpp>

#include "kernels/isa.hpp"
#include "scene_builders.hpp"

using namespace mpm;
using namespace mpm::test;

namespace {

/// Puts the active instruction set back when a test ends.
struct ActiveIsaRestored {
  Isa saved = active_isa();
  ~ActiveIsaRestored() { set_active_isa(saved); }
};

/// The instruction sets this build and CPU can run.
std::vector<Isa> runnable_isas() {
  std::vector<Isa> isas{Isa::baseline};
  if (cpu_has_avx2_fma()) isas.push_back(Isa::avx2_fma);
  return isas;
}

}  // namespace

TEST_CASE("the AVX2 copy of the kernels agrees with the baseline code to round-off", "[isa]") {
  if (!cpu_has_avx2_fma()) {
    WARN("no AVX2 copy in this build or no AVX2 + FMA on this CPU: nothing to compare");
    return;
  }
  const ActiveIsaRestored restore;
  for (const char* update : {"usl", "musl"})
    for (const char* mapping : {"direct", "tls"}) {
      auto scene = plate_scene(16, 0.05, update);
      scene["algorithm"]["mapping"] = mapping;
      set_active_isa(Isa::baseline);
      const auto baseline = state_after<2>(scene, 40, 2);
      set_active_isa(Isa::avx2_fma);
      const auto avx2 = state_after<2>(scene, 40, 2);
      const double worst = largest_field_difference(baseline, avx2, column_names_of<2>(scene));
      INFO(update << " " << mapping << ": largest difference relative to the field's magnitude " << worst);
      CHECK(worst <= 1e-12);
      // the AVX2 copy fuses multiply-adds: a difference shows that the other copy ran
      CHECK(worst > 0.0);
    }
}

TEST_CASE("every copy of the kernels is bitwise independent of the thread count", "[isa][parallel]") {
  const ActiveIsaRestored restore;
  for (const Isa isa : runnable_isas()) {
    set_active_isa(isa);
    INFO(isa_name(isa));
    for (const char* update : {"usl", "musl"}) {
      const auto scene = plate_scene(16, 0.05, update);
      CHECK(state_after<2>(scene, 40, 1) == state_after<2>(scene, 40, 2));
    }
  }
}

TEST_CASE("MPM_ISA values are checked", "[isa]") {
  CHECK(isa_for("baseline") == Isa::baseline);
  CHECK(isa_for("auto") == (cpu_has_avx2_fma() ? Isa::avx2_fma : Isa::baseline));
  CHECK_THROWS_WITH(isa_for("sse9"), Catch::Contains("MPM_ISA") && Catch::Contains("sse9"));
  if (!cpu_has_avx2_fma()) CHECK_THROWS_WITH(isa_for("avx2"), Catch::Contains("MPM_ISA = avx2"));
}
