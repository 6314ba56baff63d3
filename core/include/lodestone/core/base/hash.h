#pragma once
// FNV-1a, 64 bits: the one hash of byte strings in Lodestone (checkpoint
// checksums, the content hash of scene files). Not cryptographic: it detects
// accidental change, not tampering.
#include <cstddef>
#include <cstdint>
#include <string>

namespace lodestone {
inline namespace base {

inline constexpr std::uint64_t kFnv1a64Offset = 0xcbf29ce484222325ull;
inline constexpr std::uint64_t kFnv1a64Prime = 0x100000001b3ull;

/// The FNV-1a 64-bit hash of `size` bytes at `data`, continuing from `hash`
/// (the offset basis for a fresh hash), so that a string hashed in pieces
/// gets the hash of the whole.
inline std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t hash = kFnv1a64Offset) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    hash ^= bytes[i];
    hash *= kFnv1a64Prime;
  }
  return hash;
}

inline std::uint64_t fnv1a64(const std::string& text) { return fnv1a64(text.data(), text.size()); }

/// The hash as 16 lower-case hexadecimal digits ("cbf29ce484222325").
inline std::string hashHex(std::uint64_t hash) {
  static const char digits[] = "0123456789abcdef";
  std::string text(16, '0');
  for (int i = 15; i >= 0; --i, hash >>= 4) text[std::size_t(i)] = digits[hash & 0xf];
  return text;
}

}  // namespace base
}  // namespace lodestone
