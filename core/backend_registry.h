// Name -> factory registry of one kind of backend, as static functions over
// one process-wide Registry<Product> (core/registry.h). The two instances are
// NlpSolverRegistry (nlp.h) and IntegratorRegistry (dae.h); built-in backends
// are added by RegisterBuiltinNlpSolvers() / RegisterBuiltinIntegrators(),
// plugins call Register() themselves. The members are defined in registry.h
// and instantiated (with the registry's name for messages) in nlp.cc and
// dae.cc, so this header stays light.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "quasiroll/core/backend_info.h"

namespace quasiroll {

template <typename Product>
class Registry;

template <typename Product>
class BackendRegistry {
 public:
  using Factory = std::function<std::unique_ptr<Product>()>;
  static void Register(const std::string& name, const std::string& description,
                       Factory factory);
  // With the info a backend registers about itself (core/backend_info.h).
  // Throws std::invalid_argument for an empty name or factory, a name
  // registered already, or a role another backend has.
  static void Register(const std::string& name, BackendInfo info,
                       Factory factory);
  // Throws std::invalid_argument naming the unknown backend and the known ones.
  static std::unique_ptr<Product> Create(const std::string& name);
  static bool Has(const std::string& name);
  static std::vector<std::string> Names();
  static std::string Description(const std::string& name);
  // Empty for an unknown name.
  static BackendInfo Info(const std::string& name);
  // The first registered name (in name order) with `role`; throws
  // std::invalid_argument when none has it.
  static std::string WithRole(BackendRole role);

 private:
  // The process-wide table; specialised per Product next to the explicit
  // instantiation.
  static Registry<Product>& Instance();
};

}  // namespace quasiroll
