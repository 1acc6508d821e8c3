// SPDX-License-Identifier: MIT
// Case files: units on entry, defaults, overrides, and errors that name key, value and what is allowed.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>

#include "app/dem_scene.hpp"
#include "core/config.hpp"
#include "core/errors.hpp"
#include "solid/dem_io.hpp"
#include "solid/dem_solver.hpp"

namespace tessera {
namespace {

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(Config, UnitsConvertOnEntry) {
  Config c = Config::parse("a: {d: 0.6 mm, t: 2 ms, e: 70 GPa, rho: 2.48 g/cm^3, plain: 3.5}");
  const ConfigNode a = c.root().section("a");
  EXPECT_DOUBLE_EQ(a.real("d", Dim::length, Range::positive()), 6e-4);
  EXPECT_DOUBLE_EQ(a.real("t", Dim::time, Range::positive()), 2e-3);
  EXPECT_DOUBLE_EQ(a.real("e", Dim::pressure, Range::positive()), 7e10);
  EXPECT_DOUBLE_EQ(a.real("rho", Dim::density, Range::positive()), 2480);
  EXPECT_DOUBLE_EQ(a.real("plain", Dim::length, Range::positive()), 3.5);
  EXPECT_DOUBLE_EQ(c.resolved()["a"]["d"].as<double>(), 6e-4);  // SI in the resolved case
}

TEST(Config, WrongUnitNamesKeyValueAndAllowedUnits) {
  Config c = Config::parse("a: {d: 0.6 kg}");
  const std::string m = error_of([&] { c.root().section("a").real("d", Dim::length, Range::positive()); });
  EXPECT_NE(m.find("'a.d'"), std::string::npos) << m;
  EXPECT_NE(m.find("0.6 kg"), std::string::npos) << m;
  EXPECT_NE(m.find("mm"), std::string::npos) << m;
}

TEST(Config, OutOfRangeAndWrongType) {
  Config c = Config::parse("a: {rho: -5, n: many, law: spring, v: [1, 2]}");
  const ConfigNode a = c.root().section("a");
  EXPECT_NE(error_of([&] { a.real("rho", Dim::density, Range::positive()); }).find("> 0"), std::string::npos);
  EXPECT_NE(error_of([&] { a.integer("n", 0, 10); }).find("an integer in [0, 10]"), std::string::npos);
  EXPECT_NE(error_of([&] {
              a.choice("law", {"hooke", "hertz_mindlin"});
            }).find("one of hooke, hertz_mindlin"),
            std::string::npos);
  EXPECT_NE(error_of([&] { a.vec3("v", Dim::length); }).find("a list of 3 numbers"), std::string::npos);
}

TEST(Config, MissingKeyAndDefaults) {
  Config c = Config::parse("a: {x: 1}");
  const ConfigNode a = c.root().section("a");
  EXPECT_NE(error_of([&] { a.real("y", Dim::none, Range::any()); }).find("is required"), std::string::npos);
  EXPECT_EQ(a.real("z", Dim::none, Range::any(), 4.0), 4.0);
  EXPECT_EQ(c.resolved()["a"]["z"].as<double>(), 4.0);
}

// The resolved case must run again as it is (tools re-measure finished runs from it): lists of
// integers and of names are in it too.
TEST(Config, ResolvedCaseHoldsListsOfIntegersAndNames) {
  Config c = Config::parse("a: {cells: [64, 64, 48], names: [sand, wall]}");
  const ConfigNode a = c.root().section("a");
  a.integers("cells", 3, 1, 100);
  a.texts("names");
  const YAML::Node r = c.resolved()["a"];
  ASSERT_TRUE(r["cells"].IsSequence());
  EXPECT_EQ(r["cells"][2].as<long>(), 48);
  ASSERT_TRUE(r["names"].IsSequence());
  EXPECT_EQ(r["names"][1].as<std::string>(), "wall");
}

// A list of sections stays a list (it once came out as a mapping with keys 0, 1, which the next
// run refused), and the resolved case read again resolves to the same text.
TEST(Config, ResolvedCaseHoldsListsOfSectionsAndReadsBack) {
  auto read = [](Config& c) {
    for (const ConfigNode& p : c.root().section("a").list("pairs")) {
      p.texts("materials");
      p.real("k", Dim::none, Range::positive());
      p.real("e", Dim::none, Range::positive(), 0.5);
    }
  };
  Config c = Config::parse("a: {pairs: [{materials: [sand, sand], k: 1e6}, {materials: [sand, wall], k: 2e6}]}");
  read(c);
  const YAML::Node r = c.resolved()["a"]["pairs"];
  ASSERT_TRUE(r.IsSequence());
  ASSERT_EQ(r.size(), 2u);
  EXPECT_EQ(r[1]["k"].as<double>(), 2e6);
  EXPECT_EQ(r[1]["e"].as<double>(), 0.5);
  EXPECT_EQ(r[1]["materials"][1].as<std::string>(), "wall");
  YAML::Emitter e1;
  e1 << c.resolved();
  Config again = Config::parse(e1.c_str());
  read(again);
  YAML::Emitter e2;
  e2 << again.resolved();
  EXPECT_EQ(std::string(e1.c_str()), std::string(e2.c_str()));
}

TEST(Config, UnknownKeysAreErrors) {
  Config c = Config::parse("a: {x: 1, tpyo: 2}\nb: {y: 3}");
  c.root().section("a").real("x", Dim::none, Range::any());
  const std::string m = error_of([&] { c.check_unused(); });
  EXPECT_NE(m.find("a.tpyo"), std::string::npos) << m;
  EXPECT_NE(m.find("b"), std::string::npos) << m;
}

TEST(Config, SetOverridesAnyKeyIncludingListItems) {
  Config c = Config::parse("a: {x: 1, l: [{m: 1}, {m: 2}]}", {"a.x=5", "a.l.1.m=7", "a.new=3 mm"});
  const ConfigNode a = c.root().section("a");
  EXPECT_EQ(a.real("x", Dim::none, Range::any()), 5);
  EXPECT_EQ(a.list("l")[1].real("m", Dim::none, Range::any()), 7);
  EXPECT_DOUBLE_EQ(a.real("new", Dim::length, Range::any()), 3e-3);
  EXPECT_NE(error_of([] { Config::parse("a: 1", {"novalue"}); }).find("section.key=value"), std::string::npos);
}

const char* kDeposition = R"(
scene: deposition
domain: {box_min: [0, 0, 0], box_max: [4 mm, 4 mm, 8 mm]}
solid:
  materials: {sand: {density: 2480}}
  contact:
    law: hooke
    pairs: [{materials: [sand, sand], normal_stiffness: 2000, restitution: 0.5, friction: 0.3}]
  walls: [{type: box, min: [0, 0, 0], max: [4 mm, 4 mm, 8 mm], material: sand}]
deposition:
  material: sand
  diameter: 0.6 mm
  region_min: [0, 0, 0]
  region_max: [4 mm, 4 mm, 6 mm]
  settled_kinetic_energy: 1e-10
run: {end_time: 0.1}
)";

std::string scene_error(const std::vector<std::string>& sets) {
  return error_of([&] {
    Config c = Config::parse(kDeposition, sets);
    auto s = make_scene(c.root(), MPI_COMM_WORLD, ".");
    c.check_unused();
  });
}

TEST(Config, DepositionCaseIsValid) { EXPECT_EQ(scene_error({}), ""); }

TEST(Config, InconsistentInputIsCaughtBeforeAnyWork) {
  EXPECT_NE(scene_error({"deposition.region_max=[4 mm, 4 mm, 9 mm]"}).find("deposition.region_max"), std::string::npos);
  EXPECT_NE(scene_error({"domain.box_max=[4 mm, 0, 8 mm]"}).find("domain.box_max"), std::string::npos);
  EXPECT_NE(scene_error({"deposition.material=clay"}).find("a material defined in solid.materials (sand)"),
            std::string::npos);
  EXPECT_NE(scene_error({"solid.contact.pairs.0.normal_damping=1e-3"}).find("exactly one of"), std::string::npos);
  EXPECT_NE(scene_error({"scene=tunnel"}).find("one of deposition, bed"), std::string::npos);
  EXPECT_NE(scene_error({"deposition.lattice_spacing=0.5 mm"}).find("at least the grain's extent"), std::string::npos);
  EXPECT_NE(scene_error({"solid.walls.0.material=steel"}).find("solid.walls.0.material"), std::string::npos);
  EXPECT_NE(scene_error({"solid.frobnicate=1"}).find("solid.frobnicate"), std::string::npos);
}

// A bed scene in plane mode with a free sphere (the bunker cases' kind).
const char* kBedCase = R"(
scene: bed
domain: {box_min: [0, 0, 0], box_max: [0.32, 0.0019, 0.15]}
solid:
  plane: {normal: y, thickness: 1.9 mm}
  materials: {sand: {density: 2480}, ball: {density: 1000}}
  contact:
    law: hooke
    pairs:
      - {materials: [sand, sand], normal_stiffness: 1e5, tangential_stiffness: 2.857e4, restitution: 0.5, friction: 0.25}
      - {materials: [sand, ball], normal_stiffness: 1e5, tangential_stiffness: 2.857e4, restitution: 0.5, friction: 0.2}
  free_spheres:
    - {key: ball, material: ball, diameter: 43 mm, position: [0.16, 0, 0.12]}
bed: {file: none.h5}
run: {end_time: 0.001}
)";

// A stand-in for the checkpoint a case reads from an earlier run (the bunker cases' bed.file): two
// discs and a free sphere in plane mode, so that the scene can be built without that run.
std::string bed_fixture() {
  const std::string path = "shipped_case_bed_fixture.h5";
  Config c = Config::parse(kBedCase);
  Decomposition d(MPI_COMM_WORLD, {0, 0, 0}, {0.32, 0.0019, 0.15});
  DemSettings st = DemSettings::from_config(c.root().section("solid"));
  DemSolver dem(d, ContactModel(c.root().section("solid")), Walls(), st);
  dem.add_sphere(0, 0, 0.95e-3, {0.1, 0, 0.05}, {});
  dem.add_sphere(1, 0, 0.95e-3, {0.2, 0, 0.05}, {});
  dem.add_free_sphere("ball", 1, 0.0215, {0.16, 0, 0.12}, {});
  dem.setup();
  write_checkpoint(path, dem);
  return path;
}

// Every case file shipped in cases/ is valid: it parses, every key is known, every value in range.
// A case that reads an earlier run's checkpoint (bed.file or bodies.file under runs/) reads a stand-in.
TEST(Config, ShippedCaseFilesAreValid) {
  int checked = 0;
  const std::string fixture = std::filesystem::absolute(bed_fixture()).string();
  for (const auto& entry : std::filesystem::recursive_directory_iterator(std::string(TESSERA_SOURCE_DIR) + "/cases")) {
    if (entry.path().extension() != ".yaml") continue;
    std::vector<std::string> sets;
    {
      std::ifstream in(entry.path());
      const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      // The coupled scene reads its bed as bodies.file (at set-up only its existence and positions).
      const bool coupled = text.find("scene: coupled") != std::string::npos;
      if (text.find("file: ../../runs/") != std::string::npos)
        sets.push_back((coupled ? "bodies.file=" : "bed.file=") + fixture);
    }
    const std::string m = error_of([&] {
      Config c = Config::load(entry.path().string(), sets);
      auto s = make_scene(c.root(), MPI_COMM_WORLD, entry.path().parent_path().string());
      c.check_unused();
    });
    EXPECT_EQ(m, "") << entry.path();
    ++checked;
  }
  EXPECT_GE(checked, 2);
}

// A bed run may end when it settles: bed.min_time means nothing without bed.settled_kinetic_energy.
TEST(Config, BedSettleKeysComeTogether) {
  const std::string fixture = std::filesystem::absolute(bed_fixture()).string();
  auto error = [&](std::vector<std::string> sets) {
    sets.push_back("bed.file=" + fixture);
    return error_of([&] {
      Config c = Config::parse(kBedCase, sets);
      auto s = make_scene(c.root(), MPI_COMM_WORLD, ".");
      c.check_unused();
    });
  };
  EXPECT_EQ(error({}), "");
  EXPECT_EQ(error({"bed.settled_kinetic_energy=1e-7 J", "bed.min_time=2 ms"}), "");
  EXPECT_NE(error({"bed.min_time=2 ms"}).find("bed.min_time"), std::string::npos);
  EXPECT_NE(error({"bed.settled_kinetic_energy=-1 J"}).find("bed.settled_kinetic_energy"), std::string::npos);
}

#if defined(TESSERA_HAVE_PETSC)
// One output vocabulary for every scene: the flow scene reads output.snapshot_interval, as the dry
// scenes do; its old name field_interval still reads (with a warning at run time), both is an error.
TEST(Config, FlowSceneSharesTheOutputKeys) {
  const std::string dam = std::string(TESSERA_SOURCE_DIR) + "/cases/dam_break/martin_moyce.yaml";
  auto error = [&](const std::vector<std::string>& sets) {
    return error_of([&] {
      Config c = Config::load(dam, sets);
      auto s = make_scene(c.root(), MPI_COMM_WORLD, ".");
      c.check_unused();
    });
  };
  EXPECT_EQ(error({"output.snapshot_interval=0.1"}), "");
  EXPECT_EQ(error({"output.snapshot_interval=0", "output.field_interval=0.1"}).find("output.field_interval") !=
                std::string::npos,
            true);
  Config old = Config::parse(
      "scene: flow\ndomain: {box_min: [0, 0, 0], box_max: [1, 1, 1]}\n"
      "fluid: {cells: [4, 4, 4], liquid: {density: 1000, viscosity: 1e-3},"
      " gas: {density: 1, viscosity: 1e-5}}\n"
      "run: {end_time: 0.01}\noutput: {field_interval: 0.005}\n");
  EXPECT_EQ(error_of([&] {
              auto s = make_scene(old.root(), MPI_COMM_WORLD, ".");
              old.check_unused();
            }),
            "");
}

// A V-cycle without smoothing is not a positive-definite preconditioner (CG stopped with
// DIVERGED_INDEFINITE_PC at the first projection): refused before anything runs.
TEST(Config, MultigridNeedsSmoothing) {
  const std::string dam = std::string(TESSERA_SOURCE_DIR) + "/cases/dam_break/martin_moyce.yaml";
  auto error = [&](const std::vector<std::string>& sets) {
    return error_of([&] { auto s = make_scene(Config::load(dam, sets).root(), MPI_COMM_WORLD, "."); });
  };
  EXPECT_EQ(error({"fluid.poisson.multigrid.pre_sweeps=1", "fluid.poisson.multigrid.post_sweeps=1"}), "");
  const std::string zero = error({"fluid.poisson.multigrid.pre_sweeps=0", "fluid.poisson.multigrid.post_sweeps=0"});
  EXPECT_NE(zero.find("fluid.poisson.multigrid.pre_sweeps"), std::string::npos) << zero;
}
#endif

}  // namespace
}  // namespace tessera
