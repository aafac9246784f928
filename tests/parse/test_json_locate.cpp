// Semantic errors point at the line and column of the offending key.
#include <gtest/gtest.h>

#include "core/error.h"
#include "parse/json_locate.h"
#include "parse/scene_desc.h"
#include "support/support.h"

namespace vdbmarch {
namespace {

using test::errorOf;

TEST(JsonLocate, FindsKeysAndListItemsExactly) {
    const std::string text = "{\n  \"a\": {\"b\": [1, {\"c\": \"x\\\"y\"}, 3]},\n  \"d\": 4\n}";
    EXPECT_EQ(locateJsonPath(text, "a"), text.find("\"a\""));
    EXPECT_EQ(locateJsonPath(text, "a.b"), text.find("\"b\""));
    EXPECT_EQ(locateJsonPath(text, "a.b[1]"), text.find("{\"c\""));
    EXPECT_EQ(locateJsonPath(text, "a.b[1].c"), text.find("\"c\""));
    EXPECT_EQ(locateJsonPath(text, "a.b[2]"), text.find("3]"));
    EXPECT_EQ(locateJsonPath(text, "d"), text.find("\"d\""));  // after an escaped quote
    EXPECT_EQ(locateJsonPath(text, "a.b[3]"), std::string::npos);
    EXPECT_EQ(locateJsonPath(text, "e"), std::string::npos);
    size_t line, col;
    lineAndColumn(text, text.find("\"d\""), line, col);
    EXPECT_EQ(line, 3u);
    EXPECT_EQ(col, 3u);
}

TEST(JsonLocate, SemanticErrorsCarryLineAndColumn) {
    const std::string text = "{\n  \"media\": [\n    {\"type\": \"homogeneous\", \"g\": 1.5}\n  ]\n}\n";
    // |g| >= 1 is refused.
    std::string msg = errorOf<InputError>([&] { parseSceneText(text, "s.json"); });
    EXPECT_CONTAINS(msg, "s.json:3:29: media[0].g:");
    EXPECT_CONTAINS(msg, "1.5");
    // An override's value is not in the text: no position, but the key path.
    msg = errorOf<InputError>([&] { parseSceneText(text, "s.json", {"media.0.g=2"}); });
    EXPECT_CONTAINS(msg, "s.json: media[0].g:");
}

}  // namespace
}  // namespace vdbmarch
