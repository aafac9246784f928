// The method names of render.method / --method: every Method has one name,
// the names are distinct, and each parses back to its method.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "parse/method.h"

namespace vdbmarch {
namespace {

TEST(MethodNames, EveryMethodRoundTripsThroughParseMethod) {
    ASSERT_FALSE(allMethods().empty());
    std::set<std::string> names;
    for (Method m : allMethods()) {
        const std::string name = methodName(m);
        EXPECT_NE(name, "?") << "a Method without a name";
        EXPECT_TRUE(names.insert(name).second) << "two methods are called " << name;
        Method parsed = m == Method::Uniform ? Method::Reference : Method::Uniform;
        ASSERT_TRUE(parseMethod(name, parsed)) << name;
        EXPECT_EQ(parsed, m) << name;
        EXPECT_NE(methodList().find(name), std::string::npos) << name << " missing from: " << methodList();
    }
}

TEST(MethodNames, UnknownNamesAreRefusedAndLeaveTheOutputAlone) {
    for (const char* bad : {"", "Uniform", "uniform ", "guide", "path"}) {
        Method m = Method::Guided;
        EXPECT_FALSE(parseMethod(bad, m)) << "'" << bad << "'";
        EXPECT_EQ(m, Method::Guided) << "'" << bad << "'";
    }
}

TEST(MethodNames, LiSourcesRoundTrip) {
    for (LiSource s : {LiSource::Photons, LiSource::Cache}) {
        LiSource parsed = s == LiSource::Photons ? LiSource::Cache : LiSource::Photons;
        ASSERT_TRUE(parseLiSource(liSourceName(s), parsed)) << liSourceName(s);
        EXPECT_EQ(parsed, s);
    }
    LiSource s = LiSource::Cache;
    EXPECT_FALSE(parseLiSource("photon", s));
    EXPECT_EQ(s, LiSource::Cache);
}

}  // namespace
}  // namespace vdbmarch
