#pragma once
// Tests of how much of a file a reader reads: the bytes this process has read so far (the rchar line of
// /proc/self/io, every read() counted, page cache or not).
#include <fstream>
#include <string>

namespace snh::test {

/// Bytes read by this process so far; -1 where /proc/self/io does not say.
inline long long bytes_read() {
  std::ifstream io("/proc/self/io");
  for (std::string key; io >> key;) {
    long long value = 0;
    io >> value;
    if (key == "rchar:") return value;
  }
  return -1;
}

}  // namespace snh::test
