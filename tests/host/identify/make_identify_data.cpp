// Writes the files the `kincal identify/predict/plan/urdf` command tests use, into the folder
// given: a simulated Stanford RRP arm (host/model/robots/stanford_rrp.yaml, every parameter off
// by 1 mm / 0.1 deg, base 5 mm / 0.5 deg) measured with 0.1 mm noise:
//   meas.csv       40 random configurations with the sigma column
//   validate.csv   30 held-out configurations
//   sweeps.csv     10 readings per joint, one joint at a time (for cpa)
//   still.csv      40 random configurations with the waist held at 0.4 rad
//   mirrored.csv   meas.csv with x and y exchanged (a left-handed device frame)
//   bad_row.csv    meas.csv with a short row on line 4
//   bad_model.yaml the nominal model with an unknown convention
// (the folder is created if needed)
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <utility>

#include "host/model/model_file.hpp"
#include "tests/host/identify/simulation.hpp"

int main(int argc, char** argv) {
  using namespace kincal;
  if (argc != 3) {
    std::cerr << "usage: make_identify_data ROBOTS_DIR OUTPUT_DIR\n";
    return 2;
  }
  const std::string robots = argv[1], out = argv[2];
  std::error_code error;
  std::filesystem::create_directories(out, error);
  const model::RobotModel nominal = model::load_model(robots + "/stanford_rrp.yaml");
  std::mt19937_64 rng(2024);
  const model::RobotModel truth = sim::perturbed(nominal, rng);
  const auto write = [&](const std::string& name, const model::Dataset& d) {
    std::ofstream f(out + "/" + name);
    model::write_dataset(f, d);
    return static_cast<bool>(f);
  };
  const model::Dataset measured =
      simulation::measure(truth, sim::random_configurations(nominal, 40, rng), rng, 1e-4, false, 0.0, true);
  bool ok = write("meas.csv", measured);
  model::Dataset mirrored = measured;
  for (model::Measurement& r : mirrored.rows) std::swap(r.position.x(), r.position.y());
  ok = ok && write("mirrored.csv", mirrored);
  ok = ok && write("validate.csv", simulation::measure(truth, sim::random_configurations(nominal, 30, rng), rng, 1e-4,
                                                       false, 0.0, false));
  std::vector<std::vector<double>> sweeps;
  const std::vector<double> home = {0.1, 1.7, 0.9};
  const double spans[3] = {1.5, 1.0, 0.7};
  for (std::size_t j = 0; j < 3; ++j)
    for (int k = 0; k < 10; ++k) {
      std::vector<double> q = home;
      q[j] += spans[j] * (k / 9.0 - 0.5);
      sweeps.push_back(q);
    }
  ok = ok && write("sweeps.csv", simulation::measure(truth, sweeps, rng, 1e-4, false, 0.0, true));
  std::vector<std::vector<double>> still = sim::random_configurations(nominal, 40, rng);
  for (std::vector<double>& q : still) q[0] = 0.4;
  ok = ok && write("still.csv", simulation::measure(truth, still, rng, 1e-4, false, 0.0, true));
  std::ifstream meas(out + "/meas.csv");
  std::ofstream bad(out + "/bad_row.csv");
  std::string line;
  for (int n = 1; std::getline(meas, line); ++n) bad << (n == 4 ? line.substr(0, line.rfind(',')) : line) << '\n';
  std::ifstream model_in(robots + "/stanford_rrp.yaml");
  std::ofstream bad_model(out + "/bad_model.yaml");
  while (std::getline(model_in, line)) {
    const auto at = line.find("name: shoulder");
    if (at != std::string::npos) line.replace(line.find("convention: dh"), 14, "convention: dhx");
    bad_model << line << '\n';
  }
  ok = ok && bad && bad_model;
  if (!ok) std::cerr << "make_identify_data: cannot write into " << out << '\n';
  return ok ? 0 : 1;
}
