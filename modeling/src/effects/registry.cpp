// The effect catalogue. Adding an effect: write effects/<name>.cpp with a Make<Name>() factory
// and add one line below (docs/workbench.md).
#include "hapticlab/modeling/workbench.hpp"

namespace hapticlab::modeling::wb {

std::unique_ptr<Effect> MakeCoulomb();
std::unique_ptr<Effect> MakeViscous();
std::unique_ptr<Effect> MakeDahl();
std::unique_ptr<Effect> MakeStribeck();
std::unique_ptr<Effect> MakeAnisotropicFriction();
std::unique_ptr<Effect> MakeLoadDependentFriction();
std::unique_ptr<Effect> MakePositionDependentFriction();
std::unique_ptr<Effect> MakeHcDamping();
std::unique_ptr<Effect> MakeHcExponent();
std::unique_ptr<Effect> MakeBaseLayer();
std::unique_ptr<Effect> MakeVibrationSpeed();
std::unique_ptr<Effect> MakeVibrationForce();
std::unique_ptr<Effect> MakeVibrationDirection();

const std::vector<std::unique_ptr<Effect>>& Catalogue() {
  static const std::vector<std::unique_ptr<Effect>> kCatalogue = [] {
    std::vector<std::unique_ptr<Effect>> v;
    v.push_back(MakeCoulomb());
    v.push_back(MakeViscous());
    v.push_back(MakeDahl());
    v.push_back(MakeStribeck());
    v.push_back(MakeAnisotropicFriction());
    v.push_back(MakeLoadDependentFriction());
    v.push_back(MakePositionDependentFriction());
    v.push_back(MakeHcDamping());
    v.push_back(MakeHcExponent());
    v.push_back(MakeBaseLayer());
    v.push_back(MakeVibrationSpeed());
    v.push_back(MakeVibrationForce());
    v.push_back(MakeVibrationDirection());
    return v;
  }();
  return kCatalogue;
}

}  // namespace hapticlab::modeling::wb
