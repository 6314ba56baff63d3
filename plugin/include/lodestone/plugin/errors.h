#pragma once
// Exceptions of the node layer; the C ABI maps them to status codes.
#include "lodestone/core/base/error.h"

namespace lodestone::plugin {

/// A feature needs a component this build lacks (e.g. OpenVDB).
class NotBuilt : public Error {
 public:
  using Error::Error;
};

/// A grid or a particle set estimated too large for memory, refused before
/// anything is allocated (the C ABI: LODESTONE_ERROR_OUT_OF_MEMORY).
class TooLarge : public InvalidArgument {
 public:
  using InvalidArgument::InvalidArgument;
};

/// A node's cook failed; the message names the node and the cause.
class CookFailed : public Error {
 public:
  CookFailed(const std::string& message, bool notBuilt) : Error(message), notBuilt_(notBuilt) {}
  /// The cause was NotBuilt.
  bool notBuilt() const { return notBuilt_; }

 private:
  bool notBuilt_ = false;
};

}  // namespace lodestone::plugin
