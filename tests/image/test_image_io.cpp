#include "image/exr_io.h"
#include "image/image.h"
#include "image/metrics.h"
#include "image/png_io.h"
#include "support/support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <set>
#include <string>
#include <vector>

using namespace vdbmarch;
using test::errorOf;
using test::readBytes;
using test::writeText;

namespace {

class ImageIoTest : public ::testing::Test {
protected:
    std::string path(const std::string& name) const { return mDir / name; }
    std::set<std::string> listDir() const { return test::listDir(mDir.path()); }

    test::TempDir mDir{"image"};
};

// Values that stress float exactness: denormals, huge, negative, non-finite.
Image makeTestImage(int w, int h) {
    Image img(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            img.set(x, y, Color(x * 0.1f + 1e-3f, y * 1.7e5f, -0.3f * x * y),
                    (x + y) % 2 ? 1.f : 0.25f);
    img.set(0, 0, Color(std::numeric_limits<float>::denorm_min(), 3.4e38f, -0.f), 0.5f);
    img.set(1, 0, Color(std::numeric_limits<float>::infinity(), 1.f / 3.f, 1e-30f), 1.f);
    return img;
}

bool bitEqual(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

}  // namespace

TEST(Image, StoresPixelsRowMajorTopFirst) {
    Image img(3, 2);
    ASSERT_EQ(img.rgba.size(), 24u);
    EXPECT_EQ(img.rgb(2, 1), Color(0.f));
    EXPECT_EQ(img.alpha(2, 1), 0.f);
    img.set(2, 1, Color(1, 2, 3), 0.5f);
    EXPECT_EQ(img.rgb(2, 1), Color(1, 2, 3));
    EXPECT_EQ(img.alpha(2, 1), 0.5f);
    // Last pixel of the second row is the last 4 floats.
    EXPECT_EQ(img.rgba[20], 1.f);
    EXPECT_EQ(img.rgba[23], 0.5f);
    EXPECT_THROW(Image(-1, 2), std::logic_error);  // a caller bug: readers check sizes first
}

TEST_F(ImageIoTest, ExrRoundTripIsBitExactWithAttributes) {
    Image img = makeTestImage(7, 5);
    img.rgba[4 * 3 + 1] = std::numeric_limits<float>::quiet_NaN();
    StringAttributes attrs = {{"vdbmarch/scene", "clouds.json"}, {"vdbmarch/spp", "256"},
                              {"empty", ""}, {"utf8", "\xC3\xA9t\xC3\xA9 \"quoted\"\nnewline"}};
    writeExr(path("a.exr"), img, attrs);

    Image back = readExr(path("a.exr"));
    ASSERT_EQ(back.width, 7);
    ASSERT_EQ(back.height, 5);
    ASSERT_EQ(back.rgba.size(), img.rgba.size());
    for (size_t i = 0; i < img.rgba.size(); ++i)
        EXPECT_TRUE(bitEqual(back.rgba[i], img.rgba[i])) << "float " << i << ": " << back.rgba[i]
                                                         << " vs " << img.rgba[i];

    StringAttributes read = readExrStringAttributes(path("a.exr"));
    std::sort(attrs.begin(), attrs.end());
    EXPECT_EQ(read, attrs);  // sorted by name, and no other string attributes
    EXPECT_EQ(listDir(), std::set<std::string>{"a.exr"});  // no temp file left
}

TEST_F(ImageIoTest, ExrWriteReplacesExistingFile) {
    writeExr(path("a.exr"), makeTestImage(4, 4), {});
    Image second(2, 3);
    second.set(1, 2, Color(5, 6, 7), 1.f);
    writeExr(path("a.exr"), second, {});
    Image back = readExr(path("a.exr"));
    EXPECT_EQ(back.width, 2);
    EXPECT_EQ(back.height, 3);
    EXPECT_EQ(back.rgb(1, 2), Color(5, 6, 7));
}

TEST_F(ImageIoTest, ReadExrMissingFileNamesIt) {
    std::string p = path("missing.exr");
    EXPECT_CONTAINS(errorOf<IoError>([&] { readExr(p); }), p);
    EXPECT_THROW(readExrStringAttributes(p), IoError);
}

TEST_F(ImageIoTest, ReadExrOfNonExrFileNamesIt) {
    std::string p = path("text.exr");
    writeText(p, "this is not an OpenEXR file\n");
    EXPECT_CONTAINS(errorOf<InputError>([&] { readExr(p); }), p);
}

TEST_F(ImageIoTest, ReadExrOfTruncatedFileThrowsInputError) {
    writeExr(path("a.exr"), makeTestImage(64, 64), {});
    std::string bytes = readBytes(path("a.exr"));
    writeText(path("cut.exr"), bytes.substr(0, bytes.size() / 2));
    EXPECT_CONTAINS(errorOf<InputError>([&] { readExr(path("cut.exr")); }), path("cut.exr"));
}

// Found by fuzzing (tools/fuzz.sh, fuzz_exr): a damaged header claiming a
// 2686984 x 257 data window made a 1 kB file allocate 11 GB before OpenEXR
// noticed the data was missing. Now refused from the header, naming the file.
TEST_F(ImageIoTest, ReadExrRefusesADataWindowTheFileCannotHold) {
    writeExr(path("a.exr"), makeTestImage(8, 8), {});
    std::string bytes = readBytes(path("a.exr"));
    const std::string key = std::string("dataWindow") + '\0' + "box2i" + '\0';
    const size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    const int32_t box[4] = {0, 0, 2686983, 256};  // xmin, ymin, xmax, ymax after the 4-byte size
    std::memcpy(&bytes[at + key.size() + 4], box, sizeof box);
    writeText(path("huge.exr"), bytes);
    const std::string msg = errorOf<InputError>([&] { readExr(path("huge.exr")); });
    EXPECT_CONTAINS(msg, path("huge.exr"));
    EXPECT_CONTAINS(msg, "2686984x257");
}

// Fuzzing finding (fuzz_exr, timeout): a string attribute whose size field
// claims ~1.7 GB made OpenEXR allocate and clear that much before failing
// (over 10 s under ASan). The header walk refuses it from the size alone.
TEST_F(ImageIoTest, ReadExrRefusesAnAttributeSizeTheFileCannotHold) {
    writeExr(path("a.exr"), makeTestImage(8, 8), {{"vdbmarch:note", "hello"}});
    std::string bytes = readBytes(path("a.exr"));
    const std::string key = std::string("vdbmarch:note") + '\0' + "string" + '\0';
    const size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    const int32_t huge = 1744830468;
    std::memcpy(&bytes[at + key.size()], &huge, sizeof huge);
    writeText(path("huge.exr"), bytes);
    const std::string msg = errorOf<InputError>([&] { readExr(path("huge.exr")); });
    EXPECT_CONTAINS(msg, path("huge.exr"));
    EXPECT_CONTAINS(msg, "vdbmarch:note");
    EXPECT_CONTAINS(msg, "1744830468");
    // The untouched file still reads, attributes and all.
    EXPECT_EQ(readExr(path("a.exr")).width, 8);
    EXPECT_EQ(readExrStringAttributes(path("a.exr")).size(), 1u);
}

// Fuzzing finding (fuzz_exr, third run): OpenEXR reads a channel list by
// its entries and fixed-size types by their type, whatever the size field
// says, so a wrong size there desynchronised a walk that skipped by size and
// let a later attribute's huge size through. The walk follows OpenEXR: the
// string after a mis-sized channel list is still refused.
TEST_F(ImageIoTest, HeaderWalkFollowsOpenExrPastAMisSizedChannelList) {
    writeExr(path("a.exr"), makeTestImage(8, 8), {{"vdbmarch:note", "hello"}});
    std::string bytes = readBytes(path("a.exr"));
    auto setSize = [&](const std::string& name, const std::string& type, int32_t size) {
        const std::string key = name + '\0' + type + '\0';
        const size_t at = bytes.find(key);
        ASSERT_NE(at, std::string::npos) << name;
        std::memcpy(&bytes[at + key.size()], &size, sizeof size);
    };
    setSize("channels", "chlist", 1);
    setSize("compression", "compression", 7);
    setSize("vdbmarch:note", "string", 1744830468);
    writeText(path("bad.exr"), bytes);
    const std::string msg = errorOf<InputError>([&] { readExr(path("bad.exr")); });
    EXPECT_CONTAINS(msg, "vdbmarch:note");
    EXPECT_CONTAINS(msg, "1744830468");
}

// Every EXR that fuzz_exr flagged (tests/image/fuzz_findings: damaged size
// fields and data windows that made OpenEXR allocate hundreds of megabytes
// to gigabytes before failing) is refused by name as damaged input.
TEST(ExrFuzzFindings, EveryFindingIsRefusedNamingTheFile) {
    const std::string dir = test::sourcePath("tests/image/fuzz_findings");
    int files = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        const std::string file = entry.path().string();
        const std::string msg = errorOf<InputError>([&] { readExr(file); });
        EXPECT_CONTAINS(msg, file);
        ++files;
    }
    EXPECT_GE(files, 5);
}

TEST_F(ImageIoTest, ExrRejectsReservedAttributeWithoutTouchingExistingFile) {
    writeText(path("keep.exr"), "old contents");
    // Caller bugs (no user input reaches these): logic_error, and still no file touched.
    EXPECT_THROW(writeExr(path("keep.exr"), makeTestImage(2, 2), {{"compression", "none"}}), std::logic_error);
    EXPECT_THROW(writeExr(path("keep.exr"), makeTestImage(2, 2), {{"a", "1"}, {"a", "2"}}), std::logic_error);
    EXPECT_THROW(writeExr(path("keep.exr"), Image(), {}), std::logic_error);
    EXPECT_EQ(readBytes(path("keep.exr")), "old contents");
    EXPECT_EQ(listDir(), std::set<std::string>{"keep.exr"});
}

TEST_F(ImageIoTest, WriteIntoMissingDirectoryThrowsIoError) {
    std::string p = path("no/such/dir/a.exr");
    EXPECT_CONTAINS(errorOf<IoError>([&] { writeExr(p, makeTestImage(2, 2), {}); }), p);
    EXPECT_THROW(writePng(path("no/such/dir/a.png"), makeTestImage(2, 2)), IoError);
}

TEST_F(ImageIoTest, PngRoundTripWithinQuantisation) {
    Image img(16, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x)
            img.set(x, y, Color(x / 15.f, y / 7.f, (x * y) / 105.f * 0.01f), 1.f);
    writePng(path("a.png"), img);
    Image back = readPng(path("a.png"));
    ASSERT_EQ(back.width, 16);
    ASSERT_EQ(back.height, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 16; ++x)
            for (int c = 0; c < 3; ++c) {
                // Quantisation happens in the encoded domain: half a code value.
                float want = linearToSrgb(img.rgb(x, y)[c]), got = linearToSrgb(back.rgb(x, y)[c]);
                EXPECT_NEAR(got, want, 0.5f / 255.f + 1e-5f) << x << "," << y << "," << c;
            }
    EXPECT_EQ(back.alpha(3, 3), 1.f);
    EXPECT_EQ(listDir(), std::set<std::string>{"a.png"});
}

TEST_F(ImageIoTest, PngExposureClampAndNonFinite) {
    Image img(5, 1);
    img.set(0, 0, Color(0.25f), 1.f);
    img.set(1, 0, Color(std::nanf(""), std::numeric_limits<float>::infinity(), -1.f), 1.f);
    img.set(2, 0, Color(100.f), 1.f);
    img.set(3, 0, Color(0.f), 1.f);
    img.set(4, 0, Color(-std::numeric_limits<float>::infinity()), 1.f);
    writePng(path("e.png"), img, 2.f);  // x4: 0.25 -> 1.0
    Image back = readPng(path("e.png"));
    EXPECT_EQ(back.rgb(0, 0), Color(1.f));
    EXPECT_EQ(back.rgb(1, 0), Color(0.f));
    EXPECT_EQ(back.rgb(2, 0), Color(1.f));
    EXPECT_EQ(back.rgb(3, 0), Color(0.f));
    EXPECT_EQ(back.rgb(4, 0), Color(0.f));
    EXPECT_THROW(writePng(path("f.png"), img, std::nanf("")), std::logic_error);  // the scene parser refuses it first
}

TEST_F(ImageIoTest, ReadPngErrors) {
    EXPECT_THROW(readPng(path("missing.png")), IoError);
    writeText(path("bad.png"), "not a png");
    EXPECT_CONTAINS(errorOf<InputError>([&] { readPng(path("bad.png")); }), path("bad.png"));
}

TEST(SrgbCurve, InverseAndEndpoints) {
    EXPECT_FLOAT_EQ(linearToSrgb(0.f), 0.f);
    EXPECT_FLOAT_EQ(linearToSrgb(1.f), 1.f);
    EXPECT_NEAR(linearToSrgb(0.18f), 0.4613f, 1e-4f);  // middle grey
    for (float v = 0; v <= 1.f; v += 1.f / 64)
        EXPECT_NEAR(srgbToLinear(linearToSrgb(v)), v, 1e-6f);
}

TEST(Metrics, IdenticalImagesGiveZero) {
    Image a = makeTestImage(6, 4);
    ImageErrorStats s = compareImages(a, a);
    EXPECT_EQ(s.rmse, 0.0);
    EXPECT_EQ(s.relMse, 0.0);
    EXPECT_EQ(s.meanAbsRelError, 0.0);
    EXPECT_EQ(s.nonFiniteA, 1u);  // makeTestImage has one inf pixel
    EXPECT_EQ(s.nonFiniteB, 1u);
    EXPECT_EQ(s.pixels, 23u);
    EXPECT_EQ(s.meanA, s.meanB);
}

TEST(Metrics, ConstantOffsetGivesExactErrors) {
    Image ref(4, 3), test(4, 3);
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 4; ++x) {
            ref.set(x, y, Color(0.5f), 1.f);
            test.set(x, y, Color(0.75f), 0.f);  // alpha differs: must be ignored
        }
    ImageErrorStats s = compareImages(test, ref);
    EXPECT_EQ(s.rmse, 0.25);  // every term is dyadic, so the sum is exact
    // These terms are not exactly representable: allow summation rounding.
    EXPECT_NEAR(s.relMse, 0.0625 / (0.25 + 0.01), 1e-14);
    EXPECT_NEAR(s.meanAbsRelError, 0.25 / (0.5 + 0.01), 1e-14);
    EXPECT_DOUBLE_EQ(s.meanA, 0.75);
    EXPECT_DOUBLE_EQ(s.meanB, 0.5);
    EXPECT_EQ(s.pixels, 12u);
    EXPECT_EQ(s.nonFiniteA + s.nonFiniteB, 0u);
}

TEST(Metrics, SizeMismatchThrowsWithBothSizes) {
    test::expectErrorContaining<InputError>([] { compareImages(Image(4, 3), Image(3, 4)); }, {"4x3", "3x4"});
}

TEST(Metrics, NonFinitePixelsAreCountedAndExcluded) {
    Image ref(3, 1), test(3, 1);
    for (int x = 0; x < 3; ++x) {
        ref.set(x, 0, Color(1.f), 1.f);
        test.set(x, 0, Color(2.f), 1.f);
    }
    test.set(0, 0, Color(1.f, std::nanf(""), 1.f), 1.f);
    ref.set(1, 0, Color(std::numeric_limits<float>::infinity(), 1.f, 1.f), 1.f);
    test.set(1, 0, Color(std::nanf(""), 1.f, 1.f), 1.f);
    ImageErrorStats s = compareImages(test, ref);
    EXPECT_EQ(s.nonFiniteA, 2u);
    EXPECT_EQ(s.nonFiniteB, 1u);
    EXPECT_EQ(s.pixels, 1u);
    EXPECT_DOUBLE_EQ(s.rmse, 1.0);  // only pixel 2 (offset 1) remains
    EXPECT_TRUE(std::isfinite(s.relMse));

    // Nothing left to compare: the means are undefined, not zero.
    Image allNan(1, 1);
    allNan.set(0, 0, Color(std::nanf("")), 1.f);
    EXPECT_TRUE(std::isnan(compareImages(allNan, Image(1, 1)).rmse));
}

TEST_F(ImageIoTest, FalseColorDiff) {
    Image ref(101, 1), test(101, 1);
    for (int x = 0; x < 101; ++x) test.set(x, 0, Color(x / 100.f), 1.f);
    test.set(50, 0, Color(std::nanf("")), 1.f);
    writeFalseColorDiff(path("diff.png"), test, ref);
    Image back = readPng(path("diff.png"));
    ASSERT_EQ(back.width, 101);
    auto bytes = [&](int x) {
        Color c = back.rgb(x, 0);
        return std::vector<long>{std::lround(linearToSrgb(c.x) * 255), std::lround(linearToSrgb(c.y) * 255),
                                 std::lround(linearToSrgb(c.z) * 255)};
    };
    EXPECT_EQ(bytes(0), (std::vector<long>{0x44, 0x01, 0x54}));   // no error: viridis start
    EXPECT_EQ(bytes(100), (std::vector<long>{0xFD, 0xE7, 0x25})); // at/above p99: viridis end
    EXPECT_EQ(bytes(99), (std::vector<long>{0xFD, 0xE7, 0x25}));
    EXPECT_EQ(bytes(50), (std::vector<long>{255, 0, 255}));       // non-finite: magenta
    EXPECT_NE(bytes(30), bytes(60));                              // monotone ramp is not flat
    EXPECT_THROW(writeFalseColorDiff(path("x.png"), test, Image(2, 2)), InputError);
}
