// ctest-labels: unit
// phri::YamlReader against hostile documents (issue 37): an alias bomb ("billion laughs"), an alias
// inside its own anchor and deep nesting are refused at load with one ConfigError naming the file,
// before any loader walks them; documents within the bounds, aliases included, read as before.
#include <phri/core/error.hpp>
#include <phri/core/yaml_reader.hpp>

#include "config_error.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace {

using phri::YamlReader;
using phri::test::expect_config_error;

// `levels` anchors, each a list of `width` aliases of the one before: width^levels strings in a few
// hundred bytes (9, 9: 387 million).
std::string alias_bomb(int levels, int width) {
  std::string text = "l0: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n";
  for (int level = 1; level < levels; ++level) {
    const std::string n = std::to_string(level), previous = std::to_string(level - 1);
    text.append("l").append(n).append(": &l").append(n).append(" [");
    for (int i = 0; i < width; ++i) text.append(i == 0 ? "*l" : ", *l").append(previous);
    text.append("]\n");
  }
  return text;
}

// `depth` flow sequences, one inside the other, under the key `k`.
std::string nested_sequences(int depth) { return "k: " + std::string(depth, '[') + std::string(depth, ']') + "\n"; }

// `depth` block maps, one inside the other.
std::string nested_maps(int depth) {
  std::string text;
  for (int i = 0; i < depth; ++i) text += std::string(static_cast<std::size_t>(2 * i), ' ') + "k" + std::to_string(i) + ":\n";
  return text + std::string(static_cast<std::size_t>(2 * depth), ' ') + "1\n";
}

TEST(YamlReaderBounds, AnAliasBombIsRefusedNamingTheFile) {
  const std::string bomb = alias_bomb(9, 9);
  ASSERT_LT(bomb.size(), 600u);
  expect_config_error([&] { (void)YamlReader::load_string(bomb, "bomb.yaml"); },
                      {.mentions = {"more than 100000 YAML nodes", "aliases"}, .file = "bomb.yaml"});
}

TEST(YamlReaderBounds, AnAliasBombInAFileIsRefusedNamingTheFile) {
  const std::string path = (std::filesystem::temp_directory_path() / "phri_test_yaml_bomb.yaml").string();
  std::ofstream(path) << alias_bomb(9, 9);
  expect_config_error([&] { (void)YamlReader::load_file(path); }, {.mentions = {"alias bomb"}, .file = path});
  std::filesystem::remove(path);
}

TEST(YamlReaderBounds, AnAliasInsideItsOwnAnchorIsACycle) {
  expect_config_error([] { (void)YamlReader::load_string("a: &a [1, *a]\n", "cycle.yaml"); },
                      {.element = "a[1]", .mentions = {"cycle"}, .file = "cycle.yaml"});
  expect_config_error([] { (void)YamlReader::load_string("a: &a {b: {c: *a}}\n", "cycle.yaml"); },
                      {.element = "a.b.c", .mentions = {"cycle"}, .file = "cycle.yaml"});
}

TEST(YamlReaderBounds, NestingBeyond64LevelsIsRefused) {
  expect_config_error([] { (void)YamlReader::load_string(nested_sequences(100), "deep.yaml"); },
                      {.mentions = {"nested deeper than 64 levels"}, .file = "deep.yaml"});
  expect_config_error([] { (void)YamlReader::load_string(nested_maps(100), "deep.yaml"); },
                      {.mentions = {"nested deeper than 64 levels"}, .file = "deep.yaml"});
}

// yaml-cpp's own guard (2000 levels) says only "bad file": the message says what it is.
TEST(YamlReaderBounds, NestingBeyondTheParsersGuardSaysSo) {
  expect_config_error([] { (void)YamlReader::load_string(nested_sequences(5000), "deeper.yaml"); },
                      {.element = "", .mentions = {"invalid YAML", "nested too deeply", "line 1"}, .file = "deeper.yaml"});
}

TEST(YamlReaderBounds, DocumentsWithinTheBoundsReadAsBefore) {
  // An anchor used twice reads as its values at both places.
  const YamlReader shared = YamlReader::load_string("base: &b {x: 1.5}\nuse: *b\nagain: *b\n", "ok.yaml");
  EXPECT_DOUBLE_EQ(shared.at("use").number("x", 0.0, 10.0), 1.5);
  EXPECT_DOUBLE_EQ(shared.at("again").number("x", 0.0, 10.0), 1.5);
  // 63 levels under the root's map: within the depth limit.
  const YamlReader deep = YamlReader::load_string(nested_sequences(63), "ok.yaml");
  EXPECT_TRUE(deep.at("k").is_sequence());
  // A bomb too small to reach the node budget (1 + 9 + 81 + 729 + 6561 nodes per level, about 8000).
  const YamlReader small = YamlReader::load_string(alias_bomb(4, 9), "ok.yaml");
  EXPECT_EQ(small.at("l3").size(), 9u);
}

TEST(YamlReaderBounds, TheNodeBudgetCountsEveryNode) {
  // The root sequence and its n items: n + 1 nodes.
  auto list_of = [](int n) {
    std::string text = "[";
    for (int i = 0; i < n; ++i) text += (i == 0 ? "0" : ",0");
    return text + "]";
  };
  EXPECT_EQ(YamlReader::load_string(list_of(99999), "ok.yaml").size(), 99999u);
  expect_config_error([&] { (void)YamlReader::load_string(list_of(100000), "big.yaml"); },
                      {.element = "[99999]", .mentions = {"more than 100000 YAML nodes"}, .file = "big.yaml"});
}

}  // namespace
