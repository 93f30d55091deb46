// The C++ reference of python/tests/test_model.py: for each line of stdin holding q, qd and qdd
// (3 n hexadecimal floats), prints the model terms as the library computes them, every number a
// hexadecimal float (exact): "M" and n x n entries row by row, "h", "g", "tau" (RNEA), then "J <frame>
// <rf>" and 6 x n entries row by row for every frame in the three reference frames.
//
//   phri_py_reference URDF < cases.txt
#include <phri/model/algorithms.hpp>

#include <cstdio>
#include <iostream>
#include <sstream>
#include <string>

namespace {

void print(const char* label, const Eigen::MatrixXd& m) {
  std::printf("%s", label);
  for (int r = 0; r < m.rows(); ++r) {
    for (int c = 0; c < m.cols(); ++c) std::printf(" %a", m(r, c));
  }
  std::printf("\n");
}

void print_case(const phri::Model& model, phri::Data& data, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                const Eigen::VectorXd& qdd) {
  print("M", phri::crba(model, data, q));
  print("h", phri::nonlinear_effects(model, data, q, qd));
  print("g", phri::compute_gravity(model, data, q));
  print("tau", phri::rnea(model, data, q, qd, qdd));
  phri::forward_kinematics(model, data, q);
  phri::update_frame_placements(model, data);
  Eigen::MatrixXd jacobian(6, model.nv());
  const std::pair<phri::ReferenceFrame, const char*> frames[] = {
      {phri::ReferenceFrame::kWorld, "world"}, {phri::ReferenceFrame::kLocalWorldAligned, "local_world_aligned"},
      {phri::ReferenceFrame::kLocal, "local"}};
  for (int f = 0; f < model.num_frames(); ++f) {
    for (const auto& [rf, name] : frames) {
      phri::frame_jacobian(model, data, f, rf, jacobian);
      print(("J " + model.frame(f).name + " " + name).c_str(), jacobian);
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: phri_py_reference URDF < cases\n");
    return 2;
  }
  const phri::Model model = phri::Model::from_urdf_file(argv[1]);
  phri::Data data(model);
  const int n = model.nq();
  for (std::string line; std::getline(std::cin, line);) {
    std::istringstream in(line);
    Eigen::VectorXd values(3 * n);
    for (int i = 0; i < 3 * n; ++i) {
      std::string word;
      in >> word;
      values[i] = std::strtod(word.c_str(), nullptr);  // hexadecimal floats read exactly
    }
    print_case(model, data, values.head(n), values.segment(n, n), values.tail(n));
  }
  return 0;
}
