// SPDX-License-Identifier: MIT
// Typed errors. The app catches them, prints one message on rank 0 and exits non-zero.
#pragma once
#include <stdexcept>
#include <string>

namespace tessera {

// Bad input: names the key, the offending value and what is allowed.
class InputError : public std::runtime_error {
 public:
  InputError(std::string key, std::string value, std::string allowed)
      : std::runtime_error(format(key, value, allowed)), key_(std::move(key)) {}
  const std::string& key() const { return key_; }

 private:
  static std::string format(const std::string& key, const std::string& value, const std::string& allowed) {
    std::string m = "input error: key '" + key + "'";
    if (!value.empty()) m += " has value '" + value + "'";
    return m + ": " + allowed;
  }
  std::string key_;
};

// A run that cannot go on (blow-up, lost particle, I/O failure): the message says what and where.
class RunError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A RunError every rank reaches together (decided from global reductions): the app reports it once
// and exits cleanly instead of aborting the MPI job.
class CollectiveRunError : public RunError {
 public:
  using RunError::RunError;
};

}  // namespace tessera
