// Name -> (BackendInfo, factory) registry shared by the NLP and integrator
// plugin registries (NlpSolverRegistry in nlp.h, IntegratorRegistry in
// dae.h), and the members of their static facade BackendRegistry<Product>
// (backend_registry.h). Thread-safe.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "quasiroll/core/backend_info.h"
#include "quasiroll/core/backend_registry.h"

namespace quasiroll {

template <typename Product>
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Product>()>;

  // `kind` names the products in messages, e.g. "NLP backend".
  explicit Registry(std::string kind) : kind_(std::move(kind)) {}

  // Registers `name`. Throws std::invalid_argument for an empty name or
  // factory, and for a name that is registered already (a plugin cannot
  // shadow a built-in backend, nor two plugins each other).
  void Register(const std::string& name, BackendInfo info, Factory factory) {
    if (name.empty() || !factory)
      throw std::invalid_argument(kind_ + " registry: empty name or factory");
    std::lock_guard<std::mutex> lock(mutex_);
    if (table_.count(name) > 0)
      throw std::invalid_argument(kind_ + " '" + name +
                                  "' is registered already");
    for (BackendRole role : info.roles)
      for (const auto& entry : table_)
        if (entry.second.info.HasRole(role))
          throw std::invalid_argument(kind_ + " '" + name +
                                      "' claims the role '" + ToString(role) +
                                      "' of '" + entry.first + "'");
    table_[name] = Entry{std::move(info), std::move(factory)};
  }

  // Throws std::invalid_argument naming the unknown name and the known ones.
  std::unique_ptr<Product> Create(const std::string& name) const {
    Factory factory;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      auto it = table_.find(name);
      if (it == table_.end()) {
        std::string known;
        for (const auto& entry : table_)
          known += (known.empty() ? "" : ", ") + entry.first;
        throw std::invalid_argument("unknown " + kind_ + " '" + name +
                                    "' (known: " + known + ")");
      }
      factory = it->second.factory;
    }
    return factory();
  }

  bool Has(const std::string& name) const {
    std::lock_guard<std::mutex> lock(mutex_);
    return table_.count(name) > 0;
  }

  std::vector<std::string> Names() const {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<std::string> names;
    for (const auto& entry : table_) names.push_back(entry.first);
    return names;
  }

  std::string Description(const std::string& name) const {
    return Info(name).description;
  }

  // The registered info; an empty one for an unknown name.
  BackendInfo Info(const std::string& name) const {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = table_.find(name);
    return it == table_.end() ? BackendInfo{} : it->second.info;
  }

  // The first name (in name order) whose info has `role`. Throws
  // std::invalid_argument when none has.
  std::string WithRole(BackendRole role) const {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const auto& entry : table_)
      if (entry.second.info.HasRole(role)) return entry.first;
    throw std::invalid_argument("no " + kind_ + " has the role '" +
                                ToString(role) + "' (none registered?)");
  }

 private:
  struct Entry {
    BackendInfo info;
    Factory factory;
  };
  std::string kind_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry> table_;
};

// BackendRegistry<Product>: forwards to Instance(), which nlp.cc / dae.cc
// specialise.
template <typename Product>
void BackendRegistry<Product>::Register(const std::string& name,
                                        const std::string& description,
                                        Factory factory) {
  BackendInfo info;
  info.description = description;
  Instance().Register(name, std::move(info), std::move(factory));
}

template <typename Product>
void BackendRegistry<Product>::Register(const std::string& name,
                                        BackendInfo info, Factory factory) {
  Instance().Register(name, std::move(info), std::move(factory));
}

template <typename Product>
std::unique_ptr<Product> BackendRegistry<Product>::Create(
    const std::string& name) {
  return Instance().Create(name);
}

template <typename Product>
bool BackendRegistry<Product>::Has(const std::string& name) {
  return Instance().Has(name);
}

template <typename Product>
std::vector<std::string> BackendRegistry<Product>::Names() {
  return Instance().Names();
}

template <typename Product>
std::string BackendRegistry<Product>::Description(const std::string& name) {
  return Instance().Description(name);
}

template <typename Product>
BackendInfo BackendRegistry<Product>::Info(const std::string& name) {
  return Instance().Info(name);
}

template <typename Product>
std::string BackendRegistry<Product>::WithRole(BackendRole role) {
  return Instance().WithRole(role);
}

}  // namespace quasiroll
