#pragma once
// One lock for the URDF parser's process-wide message handler: urdfdom logs through
// console_bridge, whose output handler is a global; every loader that swaps it in to capture
// the parser's messages (model/model.cpp, sim/urdf_plant.cpp) holds this lock meanwhile, so that
// two loads on two threads never restore each other's (destroyed) handler.
#include <mutex>

namespace phri {

std::mutex& urdf_parser_mutex();

}  // namespace phri
