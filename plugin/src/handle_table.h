#pragma once
// The handles the C ABI hands out. A handle is not the object's address: it
// is an id of three fields, a 16-bit magic naming the kind of object, a
// 24-bit generation and a 24-bit slot. A slot's generation grows each time
// its object is destroyed, so a handle used after its object was destroyed
// (destroyed twice, say) no longer matches and is told apart from a live
// one, even when the slot now holds a new object (a freed slot is reused only
// after a thousand others were freed, so a generation comes back after 2^34
// destructions at the earliest); so is a handle of another kind, or a value
// the library never handed out. Lookups are safe on any
// value: nothing is dereferenced until the id is found live.
#include <cstdint>
#include <deque>
#include <shared_mutex>
#include <vector>

namespace lodestone::plugin {

enum class HandleKind : std::uint16_t { Context = 0x1C0D, Fields = 0x1F1D, Stage = 0x1575, Network = 0x1E70 };

class HandleTable {
 public:
  /// A new handle for `object` of `kind` (never 0).
  std::uintptr_t add(HandleKind kind, void* object);
  /// The object of a live handle of `kind`, or null (stale, another kind, never handed out).
  void* find(std::uintptr_t handle, HandleKind kind) const noexcept;
  /// Ends a live handle of `kind` and returns its object (null, and nothing
  /// ends, when the handle is not live).
  void* remove(std::uintptr_t handle, HandleKind kind);

 private:
  struct Slot {
    std::uint32_t generation = 0;
    HandleKind kind = HandleKind::Context;
    void* object = nullptr;  // null: free
  };
  const Slot* live(std::uintptr_t handle, HandleKind kind) const noexcept;  // caller holds the lock

  mutable std::shared_mutex mutex_;
  std::vector<Slot> slots_;
  std::deque<std::uint32_t> free_;  // indices of free slots, oldest first
};

/// The library's one table of handles.
HandleTable& handleTable();

}  // namespace lodestone::plugin
