// Fed to tests/layout/check_draw_order.sh to show that it fails (not compiled).
Eigen::Vector3d noisy(std::mt19937_64& rng) {
  std::normal_distribution<double> noise(0.0, 1e-3);
  const Eigen::Vector3d ordered{noise(rng), noise(rng), noise(rng)};
  return ordered + Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
}
