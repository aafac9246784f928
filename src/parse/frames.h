// Animation frames (--frames): the frame token in file paths and the frame
// range option. A run of '#' in a path is the frame number, zero-padded to
// the run's length: "cloud.####.vdb" at frame 7 is "cloud.0007.vdb", at frame
// 12345 "cloud.12345.vdb" (never truncated). Frames are non-negative.
#pragma once

#include <string>
#include <vector>

namespace vdbmarch {

// The largest frame number --frames accepts.
constexpr int kMaxFrame = 999999999;
// The most frames one --frames range may hold.
constexpr long long kMaxFrameCount = 1000000;

// True when `path` holds the frame token (any '#').
bool hasFrameToken(const std::string& path);

// `pattern` with every run of '#' replaced by `frame` zero-padded to the run's
// length; `pattern` itself when it has no token. `frame` must be >= 0.
std::string substituteFrame(const std::string& pattern, int frame);

// `--frames` text: "N", "A-B" or "A-B:STEP" (A <= B, STEP >= 1, all whole
// non-negative numbers) as the list of frames, in order. Throws InputError
// naming `option` and the text.
std::vector<int> parseFrameRange(const std::string& text, const std::string& option = "--frames");

}  // namespace vdbmarch
