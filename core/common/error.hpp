#pragma once
// Errors that say what is wrong and where (a field path, a file and line, a model name).
#include <stdexcept>
#include <string>

namespace demcal {

/// Invalid input: a parameter out of range, an unknown model, a malformed file.
/// `where` names the place: a field path ("contact_law.normal.k1"), or "file.yaml:12".
class InputError : public std::runtime_error {
 public:
  InputError(std::string where, std::string what)
      : std::runtime_error(where.empty() ? what : where + ": " + what),
        where_(std::move(where)),
        message_(std::move(what)) {}
  const std::string& where() const { return where_; }
  /// What is wrong, without the place.
  const std::string& message() const { return message_; }

 private:
  std::string where_;
  std::string message_;
};

/// A simulation that cannot go on: NaN, kinetic-energy explosion, escaped particles,
/// a time step above the stability limit.
class SimulationFailure : public std::runtime_error {
 public:
  enum class Reason {
    kNotFinite,
    kEnergyExplosion,
    kEscaped,
    kUnstableTimeStep,
    kContactOutOfRange
  };
  SimulationFailure(Reason reason, const std::string& what)
      : std::runtime_error(what), reason_(reason) {}
  Reason reason() const { return reason_; }

 private:
  Reason reason_;
};

const char* to_string(SimulationFailure::Reason reason);

/// A number as a message shows it: `digits` significant digits.
std::string message_number(double value, int digits = 6);

}  // namespace demcal
