// Run file output: everything written is read back bitwise by name; the .partial/rename protocol, the XDMF
// sidecar, resume by append(), and the error messages.
#include <catch2/catch.hpp>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "engine/output_h5.hpp"

namespace fs = std::filesystem;
using mpm::ColumnView;
using mpm::H5Writer;
using mpm::OutputError;

namespace {

/// A fresh directory, removed with everything in it at the end of the test.
struct TempDir {
  fs::path dir;
  TempDir() {
    std::string tmpl = (fs::temp_directory_path() / "mpm-output-h5-XXXXXX").string();
    REQUIRE(mkdtemp(tmpl.data()) != nullptr);
    dir = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  std::string file(const std::string& name) const { return (dir / name).string(); }
};

/// Equal bit for bit (so -0.0, NaN payloads and denormals count).
bool same_bits(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}

std::string slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}

const std::string kScene = R"({"dimension": 2, "grid": {"length": [1.0, 1.0], "cells": [4, 4]}, "note": "ü <&>"})";

}  // namespace

TEST_CASE("H5Writer writes a run file that reads back bitwise by name", "[output]") {
  TempDir tmp;
  const std::string path = tmp.file("run.h5");
  const std::vector<std::string> names{"t", "mass", "momentum_x"};
  const std::vector<std::vector<double>> rows{{0.0, 1.0, 0.0}, {0.1, 1.0, 1e-17}, {0.2, 1.0 - 1e-16, -2.5}};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<double> x0{0.125, -0.0, 1e-310, std::numeric_limits<double>::max(), nan};
  const std::vector<double> x1{0.1, 0.2, 0.3, 0.4, 0.5};
  const std::vector<double> v0{1.0 / 3.0, -2.0, 0.0, 5e-324, 7.0};
  const std::vector<double> big_x0{0.5, 0.75}, big_x1{0.25, 0.5};
  const std::vector<double> empty;
  const std::vector<double> ck1{1, 2, 3, 4, 5}, ck2{9, 8, 7, 6};

  {
    H5Writer w(path, kScene, 2);
    CHECK(w.path() == path);
    CHECK(fs::exists(path + ".partial"));
    w.set_metric_names(names);
    for (const auto& r : rows) w.add_metrics(r);

    const std::vector<ColumnView> s0{{"x0", x0}, {"x1", x1}, {"v0", v0}};
    w.write_snapshot(0, 0.0, s0);
    const std::vector<ColumnView> s10{{"x0", empty}, {"x1", empty}, {"m", empty}};  // no particles
    w.write_snapshot(10, 0.1, s10);
    const std::vector<ColumnView> s_big{{"x0", big_x0}, {"x1", big_x1}};  // a step with 7 digits
    w.write_snapshot(1234567, 12.5, s_big);

    const std::vector<ColumnView> c1{{"x0", ck1}};
    const std::vector<std::pair<std::string, double>> sc1{{"dt", 1e-5}, {"energy0", 3.0}};
    w.write_checkpoint(5, 0.05, c1, sc1);
    const std::vector<ColumnView> c2{{"x0", ck2}, {"v0", empty}};
    const std::vector<std::pair<std::string, double>> sc2{{"dt", 2e-5}};
    w.write_checkpoint(10, 0.1, c2, sc2);

    w.set_attribute("status", "ok");
    w.close();
    w.close();  // idempotent
  }

  SECTION("the final file replaces the temporary one, and the sidecar exists") {
    CHECK(fs::exists(path));
    CHECK_FALSE(fs::exists(path + ".partial"));
    CHECK(mpm::xdmf_path(path) == tmp.file("run.xdmf"));
    CHECK(fs::exists(tmp.file("run.xdmf")));
    CHECK_FALSE(fs::exists(tmp.file("run.xdmf.partial")));
  }

  SECTION("scene and root attributes") {
    CHECK(mpm::read_scene_attribute(path) == nlohmann::json::parse(kScene));
    CHECK(mpm::read_string_attribute(path, "/", "scene") == std::vector<std::string>{kScene});
    CHECK(mpm::read_string_attribute(path, "/", "status") == std::vector<std::string>{"ok"});
    CHECK(mpm::read_number_attribute(path, "/", "dimension") == 2);
  }

  SECTION("metrics table") {
    CHECK(mpm::read_string_attribute(path, "/metrics", "columns") == names);
    std::vector<double> flat;
    for (const auto& r : rows) flat.insert(flat.end(), r.begin(), r.end());
    CHECK(same_bits(mpm::read_dataset(path, "/metrics"), flat));
  }

  SECTION("snapshots") {
    CHECK(mpm::list_snapshots(path) == std::vector<std::string>{"000000", "000010", "1234567"});
    CHECK(mpm::list_datasets(path, "/snapshots/000000") == std::vector<std::string>{"v0", "x0", "x1"});
    CHECK(same_bits(mpm::read_dataset(path, "/snapshots/000000/x0"), x0));
    CHECK(same_bits(mpm::read_dataset(path, "/snapshots/000000/x1"), x1));
    CHECK(same_bits(mpm::read_dataset(path, "/snapshots/000000/v0"), v0));
    CHECK(mpm::read_dataset(path, "/snapshots/000010/x0").empty());
    CHECK(mpm::read_dataset(path, "/snapshots/000010/m").empty());
    CHECK(same_bits(mpm::read_dataset(path, "/snapshots/1234567/x0"), big_x0));
    CHECK(same_bits(mpm::read_dataset(path, "/snapshots/1234567/x1"), big_x1));
    CHECK(mpm::read_number_attribute(path, "/snapshots/000010", "step") == 10);
    CHECK(mpm::read_number_attribute(path, "/snapshots/000010", "time") == 0.1);
    CHECK(mpm::read_number_attribute(path, "/snapshots/1234567", "time") == 12.5);
  }

  SECTION("the second checkpoint replaced the first") {
    CHECK(mpm::list_datasets(path, "/checkpoint") == std::vector<std::string>{"v0", "x0"});
    CHECK(same_bits(mpm::read_dataset(path, "/checkpoint/x0"), ck2));
    CHECK(mpm::read_dataset(path, "/checkpoint/v0").empty());
    CHECK(mpm::read_number_attribute(path, "/checkpoint", "step") == 10);
    CHECK(mpm::read_number_attribute(path, "/checkpoint", "time") == 0.1);
    CHECK(mpm::read_number_attribute(path, "/checkpoint", "dt") == 2e-5);
    CHECK_THROWS_AS(mpm::read_number_attribute(path, "/checkpoint", "energy0"), OutputError);
    CHECK_THROWS_AS(mpm::read_dataset(path, "/checkpoint.new/x0"), OutputError);
  }

  SECTION("the XDMF sidecar mentions every snapshot by its relative reference") {
    const std::string x = slurp(tmp.file("run.xdmf"));
    CHECK(x.find("<Xdmf Version=\"3.0\">") != std::string::npos);
    CHECK(x.find("CollectionType=\"Temporal\"") != std::string::npos);
    CHECK(count(x, "<Time Value=") == 2);
    CHECK(x.find("<Grid Name=\"000000\"") != std::string::npos);
    CHECK(x.find("<Grid Name=\"1234567\"") != std::string::npos);
    // XDMF readers fail on a grid without points, so the empty snapshot is only named in a comment
    CHECK(x.find("<!-- snapshot 000010 at t = 0.1 has no particles -->") != std::string::npos);
    CHECK(x.find("<Time Value=\"12.5\"/>") != std::string::npos);
    // one (n, 3) geometry and 3-vectors, written beside the snapshot (ParaView's default reader needs both)
    CHECK(x.find(">run.h5:/xdmf/000000/geometry<") != std::string::npos);
    CHECK(x.find(">run.h5:/xdmf/1234567/geometry<") != std::string::npos);
    CHECK(x.find("<Attribute Name=\"velocity\" AttributeType=\"Vector\"") != std::string::npos);
    CHECK(x.find("GeometryType=\"XYZ\"") != std::string::npos);
    CHECK(x.find("TopologyType=\"Polyvertex\" NumberOfElements=\"5\"") != std::string::npos);
    CHECK(x.find("ItemType=\"HyperSlab\"") != std::string::npos);  // 2 of the 5 connectivity ids
    CHECK(x.find(tmp.dir.string()) == std::string::npos);
    // connectivity of the largest snapshot
    CHECK(mpm::read_dataset(path, "/xdmf/ids") == std::vector<double>{0, 1, 2, 3, 4});
  }
}

TEST_CASE("A 1D writer destroyed without close() still produces the final file", "[output]") {
  TempDir tmp;
  const std::string path = tmp.file("bar.h5");
  const std::vector<double> x0{0.25, 0.5, 0.75}, v0{0.1, -0.2, 0.3};
  {
    H5Writer w(path, R"({"dimension": 1})", 1);
    w.set_metric_names({"t", "energy"});
    w.add_metrics(std::vector<double>{0.0, 1.5});
    w.add_metrics(std::vector<double>{0.5, 1.25});
    const std::vector<ColumnView> cols{{"x0", x0}, {"v0", v0}};
    w.write_snapshot(3, 0.5, cols);
    CHECK_FALSE(fs::exists(path));
  }
  CHECK(fs::exists(path));
  CHECK_FALSE(fs::exists(path + ".partial"));
  CHECK(same_bits(mpm::read_dataset(path, "/metrics"), {0.0, 1.5, 0.5, 1.25}));
  CHECK(same_bits(mpm::read_dataset(path, "/snapshots/000003/v0"), v0));
  // the (n, 3) geometry and velocity of a 1D run, zero-padded
  CHECK(mpm::read_dataset(path, "/xdmf/000003/geometry") == std::vector<double>{0.25, 0, 0, 0.5, 0, 0, 0.75, 0, 0});
  CHECK(same_bits(mpm::read_dataset(path, "/xdmf/000003/velocity"), {0.1, 0, 0, -0.2, 0, 0, 0.3, 0, 0}));
  const std::string x = slurp(tmp.file("bar.xdmf"));
  CHECK(x.find(">bar.h5:/xdmf/000003/geometry<") != std::string::npos);
  CHECK(x.find("<Attribute Name=\"velocity\" AttributeType=\"Vector\"") != std::string::npos);
}

TEST_CASE("The background grid is shown beside the particles in every time step", "[output]") {
  TempDir tmp;
  const std::string path = tmp.file("plate.h5");
  const std::vector<double> x0{0.2, 0.7}, x1{0.1, 0.9}, axis0{0, 0.5, 1}, axis1{0, 1};
  {
    H5Writer w(path, kScene, 2);
    const std::vector<std::vector<double>> wrong{axis0};
    CHECK_THROWS_AS(w.set_grid(wrong), OutputError);  // one axis for a 2D run
    const std::vector<std::vector<double>> grid{axis0, axis1};
    w.set_grid(grid);
    const std::vector<ColumnView> cols{{"x0", x0}, {"x1", x1}};
    w.write_snapshot(0, 0.0, cols);
    w.write_snapshot(5, 0.5, cols);
    w.write_snapshot(9, 0.9, cols);
    w.discard_after(5, 0.5);  // drops snapshot 9, keeps the grid
  }
  CHECK(same_bits(mpm::read_dataset(path, "/xdmf/grid/x0"), axis0));
  CHECK(same_bits(mpm::read_dataset(path, "/xdmf/grid/x1"), axis1));
  const std::string x = slurp(tmp.file("plate.xdmf"));
  CHECK(count(x, "<Time Value=") == 2);
  CHECK(count(x, "CollectionType=\"Spatial\"") == 2);
  CHECK(count(x, "<Grid Name=\"particles\" GridType=\"Uniform\">") == 2);
  CHECK(count(x, "<Grid Name=\"grid\" GridType=\"Uniform\">") == 2);
  // VXVY lists x first; the mesh's Dimensions list the slowest axis (y) first
  CHECK(x.find("<Topology TopologyType=\"2DRectMesh\" Dimensions=\"2 3\"/>") != std::string::npos);
  CHECK(x.find("<Geometry GeometryType=\"VXVY\">") != std::string::npos);
  CHECK(x.find(">plate.h5:/xdmf/grid/x1<") != std::string::npos);
}

TEST_CASE("A 1D background grid is a row of nodes at y = 0", "[output]") {
  TempDir tmp;
  const std::string path = tmp.file("bar.h5");
  const std::vector<double> x0{0.25, 0.75}, axis0{0, 0.5, 1};
  {
    H5Writer w(path, R"({"dimension": 1})", 1);
    const std::vector<std::vector<double>> grid{axis0};
    w.set_grid(grid);
    const std::vector<ColumnView> cols{{"x0", x0}};
    w.write_snapshot(0, 0.0, cols);
  }
  const std::string x = slurp(tmp.file("bar.xdmf"));
  CHECK(x.find("<Topology TopologyType=\"2DRectMesh\" Dimensions=\"1 3\"/>") != std::string::npos);
  CHECK(x.find("<DataItem Dimensions=\"1\" Format=\"XML\">0</DataItem>") != std::string::npos);
}

namespace {

// A unit square split at its centre into four counter-clockwise triangles.
const std::vector<std::array<double, 2>> kMeshNodes{{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5, 0.5}};
const std::vector<std::array<int, 3>> kMeshTriangles{{0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};

/// The text of each time step's grid in an XDMF sidecar: from its opening tag to the next step's (or the end).
std::vector<std::string> time_steps(const std::string& xdmf, const std::vector<std::string>& steps) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < steps.size(); ++i) {
    const auto begin = xdmf.find("<Grid Name=\"" + steps[i] + "\"");
    const auto end = i + 1 < steps.size() ? xdmf.find("<Grid Name=\"" + steps[i + 1] + "\"") : xdmf.size();
    REQUIRE(begin != std::string::npos);
    REQUIRE(end != std::string::npos);
    REQUIRE(begin < end);
    out.push_back(xdmf.substr(begin, end - begin));
  }
  return out;
}

}  // namespace

TEST_CASE("A triangular background mesh is shown beside the particles in every time step", "[output][mesh]") {
  TempDir tmp;
  const std::string path = tmp.file("mesh.h5");
  const std::vector<double> x0{0.2, 0.7, 0.5}, x1{0.1, 0.9, 0.4};
  {
    H5Writer w(path, kScene, 2);
    w.set_mesh(kMeshNodes, kMeshTriangles);
    const std::vector<ColumnView> cols{{"x0", x0}, {"x1", x1}};
    w.write_snapshot(0, 0.0, cols);
    w.write_snapshot(5, 0.5, cols);
    w.write_snapshot(9, 0.9, cols);
    w.discard_after(5, 0.5);  // drops snapshot 9, keeps the mesh
  }
  // nodes × 3 with z = 0, and the triangles as written
  CHECK(same_bits(mpm::read_dataset(path, "/xdmf/mesh/geometry"), {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, 0.5, 0.5, 0}));
  CHECK(mpm::read_dataset(path, "/xdmf/mesh/topology") == std::vector<double>{0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4});
  CHECK(mpm::list_datasets(path, "/xdmf/mesh") == std::vector<std::string>{"geometry", "topology"});
  CHECK_THROWS_AS(mpm::read_dataset(path, "/xdmf/grid/x0"), OutputError);

  const std::string x = slurp(tmp.file("mesh.xdmf"));
  CHECK(count(x, "<Time Value=") == 2);
  CHECK(count(x, "<Grid Name=\"grid\"") == 0);
  CHECK(count(x, "<Topology TopologyType=\"Triangle\" NumberOfElements=\"4\">") == 2);
  CHECK(count(x, "<DataItem Dimensions=\"4 3\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">"
                 "mesh.h5:/xdmf/mesh/topology</DataItem>") == 2);
  CHECK(count(x, "<DataItem Dimensions=\"5 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">"
                 "mesh.h5:/xdmf/mesh/geometry</DataItem>") == 2);
  // each time step is a spatial collection of the particles and the mesh (ParaView shows one top-level grid)
  for (const auto& step : time_steps(x, {"000000", "000005"})) {
    CHECK(count(step, "GridType=\"Collection\" CollectionType=\"Spatial\"") == 1);
    CHECK(count(step, "<Grid Name=\"particles\" GridType=\"Uniform\">") == 1);
    CHECK(count(step, "<Grid Name=\"mesh\" GridType=\"Uniform\">") == 1);
    CHECK(count(step, "TopologyType=\"Triangle\"") == 1);
    CHECK(count(step, "<Geometry GeometryType=\"XYZ\">") == 2);  // the particles' and the mesh's
  }
  CHECK(x.find(tmp.dir.string()) == std::string::npos);

  SECTION("a continued run sets the mesh again, and the new one replaces it") {
    const std::vector<std::array<double, 2>> nodes{{0, 0}, {1, 0}, {0, 1}};
    const std::vector<std::array<int, 3>> triangles{{0, 1, 2}};
    {
      H5Writer w = H5Writer::append(path);
      w.set_mesh(nodes, triangles);
      const std::vector<ColumnView> cols{{"x0", x0}, {"x1", x1}};
      w.write_snapshot(10, 1.0, cols);
    }
    CHECK(mpm::read_dataset(path, "/xdmf/mesh/topology") == std::vector<double>{0, 1, 2});
    CHECK(same_bits(mpm::read_dataset(path, "/xdmf/mesh/geometry"), {0, 0, 0, 1, 0, 0, 0, 1, 0}));
    const std::string again = slurp(tmp.file("mesh.xdmf"));
    CHECK(count(again, "<Topology TopologyType=\"Triangle\" NumberOfElements=\"1\">") == 3);
    CHECK(count(again, "<Grid Name=\"mesh\" GridType=\"Uniform\">") == 3);
  }
}

TEST_CASE("A run has one background: set_mesh and set_grid replace each other", "[output][mesh]") {
  TempDir tmp;
  const std::vector<double> x0{0.2, 0.7}, x1{0.1, 0.9}, axis0{0, 0.5, 1}, axis1{0, 1};
  const std::vector<std::vector<double>> grid{axis0, axis1};
  const std::vector<ColumnView> cols{{"x0", x0}, {"x1", x1}};

  SECTION("set_mesh after set_grid") {
    const std::string path = tmp.file("a.h5");
    {
      H5Writer w(path, kScene, 2);
      w.set_grid(grid);
      w.set_mesh(kMeshNodes, kMeshTriangles);
      w.write_snapshot(0, 0.0, cols);
    }
    CHECK_THROWS_WITH(mpm::list_datasets(path, "/xdmf/grid"), Catch::Contains("/xdmf/grid"));
    CHECK(mpm::list_datasets(path, "/xdmf/mesh") == std::vector<std::string>{"geometry", "topology"});
    const std::string x = slurp(tmp.file("a.xdmf"));
    CHECK(count(x, "<Grid Name=\"mesh\"") == 1);
    CHECK(count(x, "<Grid Name=\"grid\"") == 0);
    CHECK(count(x, "2DRectMesh") == 0);
  }

  SECTION("set_grid after set_mesh, also in a continued run") {
    const std::string path = tmp.file("b.h5");
    {
      H5Writer w(path, kScene, 2);
      w.set_mesh(kMeshNodes, kMeshTriangles);
      w.write_snapshot(0, 0.0, cols);
    }
    {
      H5Writer w = H5Writer::append(path);
      w.set_grid(grid);
      w.write_snapshot(1, 0.1, cols);
    }
    CHECK_THROWS_WITH(mpm::list_datasets(path, "/xdmf/mesh"), Catch::Contains("/xdmf/mesh"));
    CHECK(same_bits(mpm::read_dataset(path, "/xdmf/grid/x0"), axis0));
    const std::string x = slurp(tmp.file("b.xdmf"));
    CHECK(count(x, "<Grid Name=\"grid\"") == 2);
    CHECK(count(x, "<Grid Name=\"mesh\"") == 0);
    CHECK(count(x, "Triangle") == 0);
  }
}

TEST_CASE("set_mesh rejects a bad mesh naming the file and the triangle, and the run goes on", "[output][mesh]") {
  TempDir tmp;
  const std::string path = tmp.file("bad.h5");
  H5Writer w(path, kScene, 2);
  const std::vector<std::array<double, 2>> no_nodes;
  const std::vector<std::array<int, 3>> no_triangles;
  CHECK_THROWS_WITH(w.set_mesh(no_nodes, kMeshTriangles), Catch::Contains(path) && Catch::Contains("without nodes"));
  CHECK_THROWS_WITH(w.set_mesh(kMeshNodes, no_triangles),
                    Catch::Contains(path) && Catch::Contains("without triangles"));
  const std::vector<std::array<int, 3>> past_end{{0, 1, 4}, {1, 2, 5}}, negative{{0, 1, 4}, {1, 2, 4}, {-1, 3, 4}};
  CHECK_THROWS_AS(w.set_mesh(kMeshNodes, past_end), OutputError);
  CHECK_THROWS_WITH(w.set_mesh(kMeshNodes, past_end),
                    Catch::Contains(path) && Catch::Contains("triangle 1 has node index 5, the mesh has 5 nodes"));
  CHECK_THROWS_WITH(w.set_mesh(kMeshNodes, negative), Catch::Contains(path) && Catch::Contains("triangle 2"));
  {
    H5Writer w3(tmp.file("cube.h5"), R"({"dimension": 3})", 3);
    CHECK_THROWS_WITH(w3.set_mesh(kMeshNodes, kMeshTriangles), Catch::Contains("3D run"));
  }
  // the rejected meshes wrote nothing and cost nothing: the writer still works
  const std::vector<double> x0{0.5}, x1{0.5};
  const std::vector<ColumnView> cols{{"x0", x0}, {"x1", x1}};
  w.write_snapshot(0, 0.0, cols);
  w.close();
  CHECK(mpm::list_snapshots(path) == std::vector<std::string>{"000000"});
  CHECK_THROWS_AS(mpm::list_datasets(path, "/xdmf/mesh"), OutputError);
  CHECK(count(slurp(tmp.file("bad.xdmf")), "<Grid Name=\"mesh\"") == 0);
  CHECK_THROWS_AS(w.set_mesh(kMeshNodes, kMeshTriangles), OutputError);  // after close
}

TEST_CASE("append() continues a run after its checkpoint", "[output]") {
  TempDir tmp;
  const std::string path = tmp.file("resume.h5");
  const std::vector<double> a{1, 2}, b{3, 4}, c{5, 6, 7, 8, 9}, c_new{7, 8};  // c: particles added, later undone
  {
    H5Writer w(path, kScene, 2);
    w.set_metric_names({"t", "mass"});
    for (double t : {0.0, 0.1, 0.2}) w.add_metrics(std::vector<double>{t, 1.0});
    const std::vector<ColumnView> s0{{"x0", a}}, s1{{"x0", b}}, s2{{"x0", c}};
    w.write_snapshot(0, 0.0, s0);
    w.write_snapshot(10, 0.1, s1);
    const std::vector<std::pair<std::string, double>> none;
    w.write_checkpoint(10, 0.1, s1, none);
    w.write_snapshot(20, 0.2, s2);
  }  // closed by the destructor
  {
    H5Writer w = H5Writer::append(path);
    CHECK(fs::exists(path));  // untouched until close
    CHECK(fs::exists(path + ".partial"));
    w.set_metric_names({"t", "mass"});  // same names: accepted
    CHECK_THROWS_AS(w.set_metric_names({"t"}), OutputError);
    CHECK(mpm::read_number_attribute(path, "/checkpoint", "step") == 10);
    w.discard_after(10, 0.1);
    w.add_metrics(std::vector<double>{0.2, 2.0});
    const std::vector<ColumnView> s2{{"x0", c_new}};
    w.write_snapshot(20, 0.2, s2);
    w.close();
  }
  CHECK_FALSE(fs::exists(path + ".partial"));
  CHECK(mpm::read_scene_attribute(path) == nlohmann::json::parse(kScene));
  CHECK(same_bits(mpm::read_dataset(path, "/metrics"), {0.0, 1.0, 0.1, 1.0, 0.2, 2.0}));
  CHECK(mpm::list_snapshots(path) == std::vector<std::string>{"000000", "000010", "000020"});
  CHECK(same_bits(mpm::read_dataset(path, "/snapshots/000020/x0"), c_new));
  // the ParaView geometry of the replaced snapshot is the new one, not the discarded run's
  CHECK(same_bits(mpm::read_dataset(path, "/xdmf/000020/geometry"), {7, 0, 0, 8, 0, 0}));
  const std::string x = slurp(tmp.file("resume.xdmf"));
  CHECK(count(x, "<Time Value=") == 3);
  // the connectivity helper kept its 5 ids from the first run; the 2-particle grids take a slab of it
  CHECK(x.find("Dimensions=\"5\" NumberType=\"Int\" Precision=\"8\" Format=\"HDF\">resume.h5:/xdmf/ids<") !=
        std::string::npos);
  CHECK_THROWS_AS(H5Writer::append(tmp.file("missing.h5")), OutputError);
}

TEST_CASE("Output errors are OutputError naming the file", "[output]") {
  TempDir tmp;
  const std::string bad = tmp.file("no/such/dir/run.h5");
  CHECK_THROWS_AS(H5Writer(bad, "{}", 2), OutputError);
  CHECK_THROWS_WITH(H5Writer(bad, "{}", 2), Catch::Contains(bad) && Catch::Contains("H5Fcreate"));
  CHECK_FALSE(fs::exists(bad));

  const std::string missing = tmp.file("missing.h5");
  CHECK_THROWS_WITH(mpm::read_scene_attribute(missing), Catch::Contains(missing));
  CHECK_THROWS_WITH(mpm::list_snapshots(missing), Catch::Contains(missing));

  const std::string path = tmp.file("misuse.h5");
  H5Writer w(path, "{}", 2);
  CHECK_THROWS_AS(w.add_metrics(std::vector<double>{1.0}), OutputError);  // before set_metric_names
  w.set_metric_names({"t", "mass"});
  CHECK_THROWS_AS(w.add_metrics(std::vector<double>{1.0}), OutputError);  // wrong row size
  const std::vector<double> two{1, 2}, three{1, 2, 3};
  const std::vector<ColumnView> ragged{{"x0", two}, {"x1", three}}, slash{{"a/b", two}};
  const std::vector<ColumnView> twice{{"x0", two}, {"x0", two}};
  CHECK_THROWS_AS(w.write_snapshot(1, 0.0, ragged), OutputError);
  CHECK_THROWS_AS(w.write_snapshot(1, 0.0, slash), OutputError);
  CHECK_THROWS_AS(w.write_snapshot(1, 0.0, twice), OutputError);
  CHECK_THROWS_AS(w.write_snapshot(-1, 0.0, {}), OutputError);
  const std::vector<std::pair<std::string, double>> reserved{{"step", 1.0}};
  CHECK_THROWS_AS(w.write_checkpoint(1, 0.0, {}, reserved), OutputError);
  w.close();
  CHECK_THROWS_AS(w.write_snapshot(2, 0.0, {}), OutputError);  // after close
  CHECK_THROWS_WITH(mpm::read_dataset(path, "/nothing"), Catch::Contains(path) && Catch::Contains("/nothing"));
  CHECK(mpm::list_snapshots(path).empty());
}
