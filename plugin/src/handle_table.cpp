#include "handle_table.h"

#include <mutex>

#include "lodestone/core/base/error.h"

namespace lodestone::plugin {

namespace {
static_assert(sizeof(std::uintptr_t) >= 8, "handles are 64-bit ids");
constexpr int kSlotBits = 24, kGenerationBits = 24;
constexpr std::uint64_t kSlotMask = (std::uint64_t(1) << kSlotBits) - 1;
constexpr std::uint64_t kGenerationMask = (std::uint64_t(1) << kGenerationBits) - 1;
constexpr std::size_t kQuarantine = 1024;  // freed slots waiting before one is reused

std::uintptr_t encode(HandleKind kind, std::uint32_t generation, std::uint32_t slot) {
  return std::uintptr_t((std::uint64_t(kind) << (kSlotBits + kGenerationBits)) |
                        ((std::uint64_t(generation) & kGenerationMask) << kSlotBits) | (std::uint64_t(slot) + 1));
}
}  // namespace

std::uintptr_t HandleTable::add(HandleKind kind, void* object) {
  require(object != nullptr, "a handle needs an object");
  std::unique_lock<std::shared_mutex> lock(mutex_);
  std::uint32_t slot;
  if (free_.size() > kQuarantine) {
    slot = free_.front();
    free_.pop_front();
  } else {
    require(slots_.size() < kSlotMask, "more than ", kSlotMask, " live handles");
    slot = std::uint32_t(slots_.size());
    slots_.emplace_back();
  }
  Slot& s = slots_[slot];
  s.kind = kind;
  s.object = object;
  return encode(kind, s.generation, slot);
}

const HandleTable::Slot* HandleTable::live(std::uintptr_t handle, HandleKind kind) const noexcept {
  const std::uint64_t h = handle;
  if (HandleKind(std::uint16_t(h >> (kSlotBits + kGenerationBits))) != kind) return nullptr;
  const std::uint64_t slot1 = h & kSlotMask;
  if (slot1 == 0 || slot1 > slots_.size()) return nullptr;
  const Slot& s = slots_[slot1 - 1];
  const std::uint32_t generation = std::uint32_t((h >> kSlotBits) & kGenerationMask);
  if (!s.object || s.kind != kind || (s.generation & kGenerationMask) != generation) return nullptr;
  return &s;
}

void* HandleTable::find(std::uintptr_t handle, HandleKind kind) const noexcept {
  std::shared_lock<std::shared_mutex> lock(mutex_);
  const Slot* s = live(handle, kind);
  return s ? s->object : nullptr;
}

void* HandleTable::remove(std::uintptr_t handle, HandleKind kind) {
  std::unique_lock<std::shared_mutex> lock(mutex_);
  Slot* s = const_cast<Slot*>(live(handle, kind));
  if (!s) return nullptr;
  void* object = s->object;
  s->object = nullptr;
  ++s->generation;
  free_.push_back(std::uint32_t(s - slots_.data()));
  return object;
}

HandleTable& handleTable() {
  static HandleTable table;
  return table;
}

}  // namespace lodestone::plugin
