// The kernels' instruction set, chosen at run time (kernels/isa.hpp): the AVX2 and AVX-512 copies of a portable
// build run the same scheme as the baseline code, and each copy is deterministic.
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
  for (const Isa isa : {Isa::avx2_fma, Isa::avx512})
    if (cpu_runs(isa)) isas.push_back(isa);
  return isas;
}

}  // namespace

TEST_CASE("the vector copies of the kernels agree with the baseline code to round-off", "[isa]") {
  const std::vector<Isa> isas = runnable_isas();
  if (isas.size() < 3) WARN("this build or CPU runs " << isas.size() - 1 << " of the 2 vector copies");
  const ActiveIsaRestored restore;
  for (const char* update : {"usl", "musl"})
    for (const char* mapping : {"direct", "tls"}) {
      auto scene = plate_scene(16, 0.05, update);
      scene["algorithm"]["mapping"] = mapping;
      set_active_isa(Isa::baseline);
      const auto baseline = state_after<2>(scene, 40, 2);
      for (std::size_t i = 1; i < isas.size(); ++i) {
        set_active_isa(isas[i]);
        const auto vector = state_after<2>(scene, 40, 2);
        const double worst = largest_field_difference(baseline, vector, column_names_of<2>(scene));
        INFO(isa_name(isas[i]) << ", " << update << " " << mapping
                               << ": largest difference relative to the field's magnitude " << worst);
        CHECK(worst <= 1e-12);
        // the vector copies fuse multiply-adds: a difference shows that another copy ran
        CHECK(worst > 0.0);
      }
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
  CHECK(isa_for("auto") == runnable_isas().back());  // the best
  CHECK_THROWS_WITH(isa_for("sse9"), Catch::Contains("MPM_ISA") && Catch::Contains("sse9"));
  if (!cpu_has_avx2_fma()) CHECK_THROWS_WITH(isa_for("avx2"), Catch::Contains("MPM_ISA = avx2"));
  if (cpu_has_avx512()) CHECK(isa_for("avx512") == Isa::avx512);
  else CHECK_THROWS_WITH(isa_for("avx512"), Catch::Contains("MPM_ISA = avx512"));
}
