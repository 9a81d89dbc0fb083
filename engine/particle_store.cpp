#include "engine/particle_store.hpp"

#include <stdexcept>

#include <tbb/parallel_for.h>

namespace mpm {

namespace {

const char* field_prefix(Field f) {
  switch (f) {
    case Field::position: return "x";
    case Field::reference: return "X";
    case Field::velocity: return "v";
    case Field::deformation: return "F";
    case Field::stress: return "s";
    case Field::mass: return "m";
    case Field::volume0: return "V0";
    case Field::body_constants: return "body";
    default: return "?";
  }
}

template <int Dim>
std::string component_name(Field f, int c) {
  const std::string p = field_prefix(f);
  switch (f) {
    case Field::position:
    case Field::reference:
    case Field::velocity:
    case Field::body_constants: return p + std::to_string(c);
    case Field::deformation: return p + std::to_string(c / Dim) + std::to_string(c % Dim);
    case Field::stress: {
      static const char* names2[] = {"00", "01", "11"};
      return p + (Dim == 1 ? "00" : names2[c]);
    }
    default: return p;
  }
}

constexpr int field_count = static_cast<int>(Field::count);

}  // namespace

template <int Dim>
ParticleStore<Dim>::ParticleStore(std::size_t count, FieldSet fields) : count_(count), fields_(fields) {
  for (int f = 0; f < field_count; ++f)
    if (fields.has(Field(f))) columns_[f].assign(components<Dim>(Field(f)), Column(count, 0.0));
}

template <int Dim>
std::span<double> ParticleStore<Dim>::column(Field f, int c) {
  auto& cols = columns_[static_cast<int>(f)];
  if (c < 0 || c >= static_cast<int>(cols.size()))
    throw std::logic_error("ParticleStore: column " + component_name<Dim>(f, c) + " is not allocated");
  return cols[c];
}

template <int Dim>
std::span<const double> ParticleStore<Dim>::column(Field f, int c) const {
  return const_cast<ParticleStore*>(this)->column(f, c);
}

template <int Dim>
std::vector<std::string> ParticleStore<Dim>::column_names() const {
  std::vector<std::string> names;
  for (int f = 0; f < field_count; ++f)
    if (Field(f) != Field::body_constants)
      for (int c = 0; c < static_cast<int>(columns_[f].size()); ++c)
        names.push_back(component_name<Dim>(Field(f), c));
  return names;
}

template <int Dim>
std::span<double> ParticleStore<Dim>::column(const std::string& name) {
  for (int f = 0; f < field_count; ++f)
    for (int c = 0; c < static_cast<int>(columns_[f].size()); ++c)
      if (component_name<Dim>(Field(f), c) == name) return columns_[f][c];
  throw std::logic_error("ParticleStore: no column named " + name);
}

template <int Dim>
std::span<const double> ParticleStore<Dim>::column(const std::string& name) const {
  return const_cast<ParticleStore*>(this)->column(name);
}

template <int Dim>
std::size_t ParticleStore<Dim>::bytes_per_particle() const {
  std::size_t n = 0;
  for (const auto& cols : columns_) n += cols.size();
  return n * sizeof(double);
}

template <int Dim>
ParticleView<Dim> ParticleStore<Dim>::view() {
  ParticleView<Dim> v;
  auto ptr = [&](Field f, int c) -> double* {
    auto& cols = columns_[static_cast<int>(f)];
    return c < static_cast<int>(cols.size()) ? cols[c].data() : nullptr;
  };
  for (int d = 0; d < Dim; ++d) {
    v.x[d] = ptr(Field::position, d);
    v.X[d] = ptr(Field::reference, d);
    v.v[d] = ptr(Field::velocity, d);
  }
  for (int c = 0; c < Dim * Dim; ++c) v.F[c] = ptr(Field::deformation, c);
  for (int c = 0; c < sym_components<Dim>; ++c) v.s[c] = ptr(Field::stress, c);
  v.m = ptr(Field::mass, 0);
  v.V0 = ptr(Field::volume0, 0);
  return v;
}

template <int Dim>
void ParticleStore<Dim>::permute(std::span<const unsigned> order) {
  if (order.size() != count_) throw std::logic_error("ParticleStore::permute: order has the wrong size");
  scratch_.resize(count_);
  for (auto& cols : columns_)
    for (auto& col : cols) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count_, 4096), [&](const auto& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) scratch_[k] = col[order[k]];
      });
      col.swap(scratch_);
    }
}

template class ParticleStore<1>;
template class ParticleStore<2>;

}  // namespace mpm
