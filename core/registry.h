// Name -> factory registry shared by the NLP and integrator plugin registries
// (NlpSolverRegistry in nlp.h, IntegratorRegistry in dae.h). Thread-safe.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace quasiroll {

template <typename Product>
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Product>()>;

  // `kind` names the products in messages, e.g. "NLP backend".
  explicit Registry(std::string kind) : kind_(std::move(kind)) {}

  // Registers (or replaces) `name`. Throws std::invalid_argument for an
  // empty name or factory.
  void Register(const std::string& name, const std::string& description,
                Factory factory) {
    if (name.empty() || !factory)
      throw std::invalid_argument(kind_ + " registry: empty name or factory");
    std::lock_guard<std::mutex> lock(mutex_);
    table_[name] = Entry{description, std::move(factory)};
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
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = table_.find(name);
    return it == table_.end() ? std::string() : it->second.description;
  }

 private:
  struct Entry {
    std::string description;
    Factory factory;
  };
  std::string kind_;
  mutable std::mutex mutex_;
  std::map<std::string, Entry> table_;
};

}  // namespace quasiroll
