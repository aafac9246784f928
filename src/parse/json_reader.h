// Typed, validating access to one JSON object of the scene file. Every error
// names the file, the key path (e.g. media[0].g) and the bad value; keys that
// nobody reads are reported with the nearest known key as a suggestion.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/math.h"

namespace vdbmarch {

using Json = nlohmann::json;

// Levenshtein distance, for "did you mean" suggestions.
size_t editDistance(const std::string& a, const std::string& b);
// Nearest candidate within a small edit distance, or "".
std::string nearestKey(const std::string& key, const std::vector<std::string>& candidates);

class JsonReader {
public:
    // `path` is the key path of this object ("" for the document root).
    JsonReader(const Json& object, std::string file, std::string path);

    // Fails on any key not in `known`, suggesting the nearest one.
    void allowOnly(const std::vector<std::string>& known) const;

    bool has(const char* key) const;
    const Json& raw(const char* key) const;
    std::string keyPath(const char* key) const;
    std::string keyPath(const char* key, size_t index) const;
    [[noreturn]] void fail(const char* key, const std::string& message) const;

    double number(const char* key) const;  // required
    double number(const char* key, double fallback) const;
    double numberIn(const char* key, double fallback, double lo, double hi) const;
    double positive(const char* key, double fallback) const;  // > 0, finite
    int integer(const char* key, int fallback, int lo, int hi) const;
    bool boolean(const char* key, bool fallback) const;
    std::string string(const char* key) const;  // required
    std::string string(const char* key, const std::string& fallback) const;
    std::string choice(const char* key, const std::string& fallback,
                       const std::vector<std::string>& allowed) const;
    Vec3 vec3(const char* key) const;  // required, finite
    Vec3 vec3(const char* key, const Vec3& fallback) const;
    Vec3 nonNegativeColor(const char* key, const Vec3& fallback) const;
    Vec3 unitDirection(const char* key) const;  // required, non-zero, normalised
    JsonReader object(const char* key) const;   // required object
    const std::string& file() const { return mFile; }
    const std::string& path() const { return mPath; }
    const Json& json() const { return mObject; }

private:
    const Json& mObject;
    std::string mFile, mPath;
};

// Short textual form of a JSON value for messages (truncated).
std::string jsonExcerpt(const Json& value);

}  // namespace vdbmarch
