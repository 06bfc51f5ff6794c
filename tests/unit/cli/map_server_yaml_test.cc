#include "cli/map_server_yaml.h"

#include <gtest/gtest.h>

namespace rmap::cli {
namespace {

TEST(MapServerYaml, YamlLiesBesideThePgm) {
  EXPECT_EQ(yamlPathFor("out/floor.pgm"), std::filesystem::path("out/floor.yaml"));
  EXPECT_EQ(yamlPathFor("floor"), std::filesystem::path("floor.yaml"));
  EXPECT_EQ(yamlPathFor("a.b/map.v2.pgm"), std::filesystem::path("a.b/map.v2.yaml"));
}

TEST(MapServerYaml, ImageLineNamesThePgm) {
  const std::string server = "image: grid2d.pgm\nresolution: 0.05\norigin: [-0.3, -0.25, 0.0]\nnegate: 0\n";
  EXPECT_EQ(withImage(server, "floor.pgm"), "image: floor.pgm\nresolution: 0.05\norigin: [-0.3, -0.25, 0.0]\nnegate: 0\n");
  EXPECT_EQ(withImage("resolution: 0.05\n", "f.pgm"), "image: f.pgm\nresolution: 0.05\n");
}

TEST(MapServerYaml, LayerVersionOfEtags) {
  EXPECT_EQ(layerVersionOf("\"7-142-pgm\""), "7-142");
  EXPECT_EQ(layerVersionOf("\"7-142-yaml\""), layerVersionOf("\"7-142-pgm\""));
  EXPECT_NE(layerVersionOf("\"7-143-yaml\""), layerVersionOf("\"7-142-pgm\""));
  EXPECT_EQ(layerVersionOf(""), "");
  EXPECT_EQ(layerVersionOf("\"7\""), "");
}

}  // namespace
}  // namespace rmap::cli
