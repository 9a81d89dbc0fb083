#pragma once
// Structure-of-arrays particle storage: one aligned, contiguous column per scalar component. Only the fields a
// scene's pipeline reads or writes are allocated; reordering (by cell, for locality) permutes every column.
#include <array>
#include <cstddef>
#include <cstdint>
#include <new>
#include <span>
#include <string>
#include <vector>

#include "kernels/views.hpp"

namespace mpm {

/// 64-byte aligned allocator: columns start on a cache line, so vector loads never split one.
template <class T>
struct AlignedAllocator {
  using value_type = T;
  static constexpr std::align_val_t alignment{64};
  AlignedAllocator() = default;
  template <class U>
  AlignedAllocator(const AlignedAllocator<U>&) {}
  T* allocate(std::size_t n) { return static_cast<T*>(::operator new(n * sizeof(T), alignment)); }
  void deallocate(T* p, std::size_t) { ::operator delete(p, alignment); }
  template <class U>
  bool operator==(const AlignedAllocator<U>&) const { return true; }
};

using Column = std::vector<double, AlignedAllocator<double>>;

/// The particle fields a pipeline may need; each has one column per component. body_constants are what a body
/// force takes from the fixed reference position, formed once from it (Problem::form_body_constants; the plate's
/// sin k X_d and cos k X_d): derived, so not part of the state (column_names) that outputs and checkpoints hold.
enum class Field : std::uint8_t {
  position, reference, velocity, deformation, stress, mass, volume0, body_constants, count
};

template <int Dim>
constexpr int components(Field f) {
  switch (f) {
    case Field::position:
    case Field::reference:
    case Field::velocity: return Dim;
    case Field::deformation: return Dim * Dim;
    case Field::stress: return sym_components<Dim>;
    case Field::body_constants: return 2 * Dim;
    default: return 1;
  }
}

/// A set of fields, as a bit mask.
struct FieldSet {
  std::uint32_t bits = 0;
  FieldSet& add(Field f) { bits |= 1u << static_cast<int>(f); return *this; }
  bool has(Field f) const { return bits & (1u << static_cast<int>(f)); }
};

template <int Dim>
class ParticleStore {
 public:
  ParticleStore(std::size_t count, FieldSet fields);

  std::size_t size() const { return count_; }
  FieldSet fields() const { return fields_; }
  bool has(Field f) const { return fields_.has(f); }

  /// Component c of field f (throws std::logic_error if the field was not allocated).
  std::span<double> column(Field f, int c = 0);
  std::span<const double> column(Field f, int c = 0) const;

  /// Names of the allocated state columns, in storage order (x0, x1, X0, ..., m, V0): all but the body constants.
  std::vector<std::string> column_names() const;
  /// Column by its name (as listed by column_names()).
  std::span<double> column(const std::string& name);
  std::span<const double> column(const std::string& name) const;

  std::size_t bytes_per_particle() const;

  /// Plain pointer view for the kernels; fields not allocated are null.
  ParticleView<Dim> view();

  /// Applies new[k] = old[order[k]] to every column.
  void permute(std::span<const unsigned> order);

 private:
  std::size_t count_;
  FieldSet fields_;
  std::array<std::vector<Column>, static_cast<int>(Field::count)> columns_;
  Column scratch_;
};

extern template class ParticleStore<1>;
extern template class ParticleStore<2>;

}  // namespace mpm
