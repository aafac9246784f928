#include "parse/json_reader.h"

#include <cmath>

#include "core/error.h"

namespace vdbmarch {

size_t editDistance(const std::string& a, const std::string& b) {
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            size_t sub = prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1);
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, sub});
        }
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

std::string nearestKey(const std::string& key, const std::vector<std::string>& candidates) {
    std::string best;
    size_t bestDist = std::max<size_t>(3, key.size() / 2) + 1;
    for (const auto& c : candidates) {
        size_t d = editDistance(key, c);
        if (d < bestDist) {
            bestDist = d;
            best = c;
        }
    }
    return best;
}

std::string jsonExcerpt(const Json& value) {
    std::string s = value.dump();
    if (s.size() > 60) s = s.substr(0, 57) + "...";
    return s;
}

JsonReader::JsonReader(const Json& object, std::string file, std::string path)
    : mObject(object), mFile(std::move(file)), mPath(std::move(path)) {
    if (!mObject.is_object())
        throw InputError(str(mFile, ": ", mPath.empty() ? "the document" : mPath,
                             " must be a JSON object, got ", jsonExcerpt(mObject)));
}

void JsonReader::allowOnly(const std::vector<std::string>& known) const {
    for (auto it = mObject.begin(); it != mObject.end(); ++it) {
        bool ok = false;
        for (const auto& k : known) ok = ok || (k == it.key());
        if (ok) continue;
        std::string msg = str("unknown key '", keyPath(it.key().c_str()), "'");
        std::string near = nearestKey(it.key(), known);
        if (!near.empty()) msg += str(" (did you mean '", near, "'?)");
        else {
            msg += "; known keys here:";
            for (const auto& k : known) msg += " " + k;
        }
        throw SceneKeyError(mFile, keyPath(it.key().c_str()), msg);
    }
}

bool JsonReader::has(const char* key) const { return mObject.contains(key); }

const Json& JsonReader::raw(const char* key) const {
    if (!has(key)) fail(key, "is required but missing");
    return mObject.at(key);
}

std::string JsonReader::keyPath(const char* key) const {
    return mPath.empty() ? std::string(key) : mPath + "." + key;
}

std::string JsonReader::keyPath(const char* key, size_t index) const {
    return str(keyPath(key), "[", index, "]");
}

void JsonReader::fail(const char* key, const std::string& message) const {
    throw SceneKeyError(mFile, keyPath(key), str(keyPath(key), ": ", message));
}

double JsonReader::number(const char* key) const {
    const Json& v = raw(key);
    if (!v.is_number()) fail(key, str("must be a number, got ", jsonExcerpt(v)));
    double d = v.get<double>();
    if (!std::isfinite(d)) fail(key, str("must be finite, got ", d));
    return d;
}

double JsonReader::number(const char* key, double fallback) const {
    return has(key) ? number(key) : fallback;
}

double JsonReader::numberIn(const char* key, double fallback, double lo, double hi) const {
    double d = number(key, fallback);
    if (d < lo || d > hi) fail(key, str("must be in [", lo, ", ", hi, "], got ", d));
    return d;
}

double JsonReader::positive(const char* key, double fallback) const {
    double d = number(key, fallback);
    if (!(d > 0)) fail(key, str("must be positive, got ", d));
    return d;
}

int JsonReader::integer(const char* key, int fallback, int lo, int hi) const {
    if (!has(key)) return fallback;
    const Json& v = raw(key);
    if (!v.is_number_integer() && !(v.is_number_float() && std::floor(v.get<double>()) == v.get<double>()))
        fail(key, str("must be an integer, got ", jsonExcerpt(v)));
    double d = v.get<double>();
    if (d < lo || d > hi) fail(key, str("must be in [", lo, ", ", hi, "], got ", jsonExcerpt(v)));
    return int(d);
}

bool JsonReader::boolean(const char* key, bool fallback) const {
    if (!has(key)) return fallback;
    const Json& v = raw(key);
    if (!v.is_boolean()) fail(key, str("must be true or false, got ", jsonExcerpt(v)));
    return v.get<bool>();
}

std::string JsonReader::string(const char* key) const {
    const Json& v = raw(key);
    if (!v.is_string()) fail(key, str("must be a string, got ", jsonExcerpt(v)));
    return v.get<std::string>();
}

std::string JsonReader::string(const char* key, const std::string& fallback) const {
    return has(key) ? string(key) : fallback;
}

std::string JsonReader::choice(const char* key, const std::string& fallback,
                               const std::vector<std::string>& allowed) const {
    std::string s = string(key, fallback);
    for (const auto& a : allowed)
        if (a == s) return s;
    std::string msg = str("unknown value \"", s, "\"");
    std::string near = nearestKey(s, allowed);
    if (!near.empty()) msg += str(" (did you mean \"", near, "\"?)");
    msg += "; expected one of:";
    for (const auto& a : allowed) msg += " " + a;
    fail(key, msg);
}

Vec3 JsonReader::vec3(const char* key) const {
    const Json& v = raw(key);
    if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
        fail(key, str("must be an array of 3 numbers, got ", jsonExcerpt(v)));
    Vec3 r(v[0].get<float>(), v[1].get<float>(), v[2].get<float>());
    if (!isFinite(r)) fail(key, str("must be finite, got ", jsonExcerpt(v)));
    return r;
}

Vec3 JsonReader::vec3(const char* key, const Vec3& fallback) const {
    return has(key) ? vec3(key) : fallback;
}

Vec3 JsonReader::nonNegativeColor(const char* key, const Vec3& fallback) const {
    if (!has(key)) return fallback;
    const Json& v = raw(key);
    Vec3 c;
    if (v.is_number()) {
        c = Vec3(v.get<float>());
        if (!std::isfinite(c.x)) fail(key, str("must be finite, got ", jsonExcerpt(v)));
    } else {
        c = vec3(key);
    }
    if (c.x < 0 || c.y < 0 || c.z < 0) fail(key, str("must not be negative, got ", jsonExcerpt(v)));
    return c;
}

Vec3 JsonReader::unitDirection(const char* key) const {
    Vec3 d = vec3(key);
    float len = length(d);
    if (!(len > 0) || !std::isfinite(len)) fail(key, str("must be a non-zero direction, got ", jsonExcerpt(raw(key))));
    return d / len;
}

JsonReader JsonReader::object(const char* key) const {
    const Json& v = raw(key);
    if (!v.is_object()) fail(key, str("must be an object, got ", jsonExcerpt(v)));
    return JsonReader(v, mFile, keyPath(key));
}

}  // namespace vdbmarch
