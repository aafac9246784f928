// FNV-1a, 64-bit: the one byte hash of the project (cache checksums, scene
// hashes, mesh welding, sample fingerprints). Not cryptographic.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace vdbmarch {

struct Fnv1a {
    uint64_t value = 1469598103934665603ULL;
    void add(const void* data, size_t n) {
        const auto* p = static_cast<const unsigned char*>(data);
        for (size_t i = 0; i < n; ++i) {
            value ^= p[i];
            value *= 1099511628211ULL;
        }
    }
    template <typename T>
    void addValue(const T& v) {
        add(&v, sizeof v);
    }
};

inline uint64_t fnv1a64(const void* data, size_t n) {
    Fnv1a h;
    h.add(data, n);
    return h.value;
}
inline uint64_t fnv1a64(const std::string& s) { return fnv1a64(s.data(), s.size()); }

}  // namespace vdbmarch
