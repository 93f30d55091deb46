#pragma once
// Self-collision capsules fitted from a URDF (issue 16), written as a collision.yaml that
// CollisionModel::from_yaml_string reads (robots/<robot>/collision.yaml stays optional):
//
//   const phri::CapsuleFit fit = phri::fit_capsules(urdf_text, model, home_q);
//   std::ofstream("robots/my_arm/collision.yaml") << fit.yaml;     // review, then commit it
//
// One capsule per link that moves with a body of its own:
//   - from the link's <collision> geometry when it has some (boxes, cylinders, spheres; a mesh
//     cannot be read here and counts as none): the axis is the principal direction of the
//     geometry's corner points, the segment spans their projections, the radius their largest
//     distance from the axis (a capsule that encloses the geometry);
//   - otherwise from the link frames: the segment from the link's origin to its child joint's
//     origin (the next link along the chain), with options.link_frame_radius_m.
// Pairs: every two capsules on bodies neither equal nor adjacent (connected by one joint, whose
// capsules meet at the joint by construction), except those closer than options.clearance_m at
// the home posture (in contact by design, as MoveIt's setup assistant disables them); the
// `notes` say which were left out and why.
#include <phri/model/model.hpp>

#include <Eigen/Core>

#include <string>
#include <vector>

namespace phri {

struct CapsuleFitOptions {
  double link_frame_radius_m = 0.04;  ///< links without collision geometry (an arm link is ~0.08 m across)
  double clearance_m = 0.0;           ///< pairs closer than this at the home posture are left out
};

struct CapsuleFit {
  std::string yaml;                ///< collision.yaml text, one capsule per line, pairs after
  int capsules = 0;
  int pairs = 0;
  std::vector<std::string> notes;  ///< links without a capsule, pairs left out at the home posture
};

/// `model` is the controller's model of the same URDF; `home_q` has model.nq() entries. Throws
/// phri::ConfigError when the URDF cannot be parsed or home_q has the wrong size.
CapsuleFit fit_capsules(const std::string& urdf, const Model& model, const Eigen::VectorXd& home_q,
                        const CapsuleFitOptions& options = {});

}  // namespace phri
