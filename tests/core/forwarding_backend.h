#pragma once
// A Backend that hands every call to another one, for tests that change or
// watch a few of them (derive and override those).
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/sim/backend.h"

namespace organsim::test {

class ForwardingBackend : public Backend {
 public:
  explicit ForwardingBackend(std::unique_ptr<Backend> inner) : inner_(std::move(inner)) {}

  std::string name() const override { return inner_->name(); }
  std::string device() const override { return inner_->device(); }
  std::string precision() const override { return inner_->precision(); }
  Plan plan() const override { return inner_->plan(); }
  const StepPlan& step_plan() const override { return inner_->step_plan(); }
  int32_t reaction_latency_ticks() const override { return inner_->reaction_latency_ticks(); }
  int32_t default_check_interval_ticks() const override { return inner_->default_check_interval_ticks(); }
  Reaction tick(const TickRequest& request) override { return inner_->tick(request); }
  void attach(const Attachment& a) override { inner_->attach(a); }
  void release() override { inner_->release(); }
  void positions(std::vector<Vec3>& out) const override { inner_->positions(out); }
  void reaction_positions(std::vector<Vec3>& out) const override { inner_->reaction_positions(out); }
  void set_state(const std::vector<Vec3>& x, const std::vector<Vec3>& x_prev) override { inner_->set_state(x, x_prev); }
  std::unique_ptr<PreparedModel> prepare(const Model& next) const override { return inner_->prepare(next); }
  void adopt(std::unique_ptr<PreparedModel> prepared) override { inner_->adopt(std::move(prepared)); }
  double time() const override { return inner_->time(); }

 protected:
  std::unique_ptr<Backend> inner_;
};

}  // namespace organsim::test
