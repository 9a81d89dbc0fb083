// The particle columns' allocator: cache-line alignment below 2 MiB, huge-page alignment from 2 MiB on, and
// columns that keep their values across growth past that size.
#include <cstdint>
#include <vector>

#include <catch2/catch.hpp>

#include "engine/particle_store.hpp"

using namespace mpm;

namespace {
std::uintptr_t address(const Column& c) { return reinterpret_cast<std::uintptr_t>(c.data()); }
}  // namespace

TEST_CASE("columns start on a cache line, and from 2 MiB on a 2 MiB page", "[store]") {
  constexpr std::size_t huge_page = ColumnAllocator<double>::huge_page;
  const Column small(1000, 1.0);
  CHECK(address(small) % 64 == 0);
  const Column just_below(huge_page / sizeof(double) - 1, 1.0), at(huge_page / sizeof(double), 1.0);
  CHECK(address(just_below) % 64 == 0);
  CHECK(address(at) % huge_page == 0);
  const Column large(3 * huge_page / sizeof(double) + 5, 1.0);  // not a whole number of pages
  CHECK(address(large) % huge_page == 0);
}

TEST_CASE("a column growing past 2 MiB keeps its values", "[store]") {
  Column c;
  const std::size_t n = 2 * ColumnAllocator<double>::huge_page / sizeof(double);
  for (std::size_t k = 0; k < n; ++k) c.push_back(static_cast<double>(k));  // reallocates across the threshold
  bool kept = true;
  for (std::size_t k = 0; k < n; ++k) kept = kept && c[k] == static_cast<double>(k);
  CHECK(kept);
  c.resize(10);
  c.shrink_to_fit();  // back below the threshold: freed with the size and alignment it was allocated with
  CHECK(c.back() == 9.0);
  CHECK(address(c) % 64 == 0);
}

TEST_CASE("the particle store's columns of a million particles lie on huge pages, also after a permutation",
          "[store]") {
  constexpr std::size_t huge_page = ColumnAllocator<double>::huge_page;
  ParticleStore<2> store(1'000'000, FieldSet{}.add(Field::position).add(Field::velocity));
  const auto on_huge_pages = [&] {
    bool all = true;
    for (Field f : {Field::position, Field::velocity})
      for (int d = 0; d < 2; ++d)
        all = all && reinterpret_cast<std::uintptr_t>(store.column(f, d).data()) % huge_page == 0;
    return all;
  };
  CHECK(on_huge_pages());
  std::vector<unsigned> reversed(store.size());
  for (std::size_t k = 0; k < reversed.size(); ++k) reversed[k] = static_cast<unsigned>(reversed.size() - 1 - k);
  store.permute(reversed);  // swaps every column with the store's scratch column
  CHECK(on_huge_pages());
}
