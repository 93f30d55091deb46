// Built against the installed phri package only: loads a URDF given on the command line and
// checks that the library links and runs.
#include <phri/core/version.hpp>
#include <phri/model/model.hpp>
#include <phri/model/algorithms.hpp>

#include <cstdio>

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: consumer URDF\n");
    return 2;
  }
  const phri::Model model = phri::Model::from_urdf_file(argv[1]);
  phri::Data data(model);
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(model.nq());
  phri::compute_gravity(model, data, q);
  std::printf("phri %s: %s has %d joints, |g(0)| = %.6f\n", phri::version(), model.name().c_str(),
              model.nq(), data.gravity_torque.norm());
  return model.nq() > 0 ? 0 : 1;
}
