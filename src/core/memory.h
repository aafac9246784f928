// Memory the machine can give this process, and the up-front check that
// refuses a job which cannot fit (a resolution, a photon count, a grid) with
// a message that says how much it would need, instead of being killed by the
// kernel half-way through.
#pragma once

#include <cstdint>
#include <string>

namespace vdbmarch {

// Physical memory, or the cgroup limit (containers, Slurm) when smaller.
uint64_t availableMemoryBytes();

// Throws InputError("<what> needs about X GiB of memory; this machine has Y
// GiB") when `bytes` exceeds the available memory.
void checkMemory(uint64_t bytes, const std::string& what);

// Resident memory of this process now, and its peak so far (VmHWM), in bytes;
// 0 where /proc is not readable.
uint64_t residentMemoryBytes();
uint64_t peakResidentMemoryBytes();

// "12.3 GiB", "456 MiB".
std::string formatBytes(uint64_t bytes);

}  // namespace vdbmarch
