// Times Pinocchio's articulated-body algorithm (ABA, forward dynamics) on the models of
// `cargo bench -p generator --bench pinocchio`, built as Pinocchio users build them: a
// free-flyer joint for a floating base, revolute and prismatic joints for the rest, the same
// masses, inertias, offsets and gravity as the RON models and `generator::model::examples`.
//
//   aba MODEL [N]         MODEL: three_body | satellite_boom | pendulum_on_cart | floating_chain
//   aba MODEL N accel     reads a state from stdin, prints ABA's accelerations
//   aba saved MODEL [layout | accel]
//                         a robot: times ABA and CRBA with Cholesky | prints each joint's
//                         place in q and v | prints the accelerations at a state read from stdin
//
// A robot is read from its URDF by Pinocchio's own parser (`pin.buildModelFromUrdf`, in Python)
// and saved as Pinocchio's text archive (`save_robot.py`), which this program loads: the
// wheel's compiled parser cannot be called from code built for newer instructions (its Eigen
// objects are laid out for SSE2: it crashes), the archive's loader is all headers. Mimic joints
// are saved free (independent joints): ABA and Pinocchio's Cholesky take no mimic joint, and a
// mimic joint loaded from the archive crashes CRBA.
//
// Prints `aba NS`: the best, over 7 rounds, of the mean time of 200 calls at one state (the
// same rounds and calls as the timing program of our modules). Built by the benchmark with
// `g++ -O3 -march=native` against the headers and library of the `pin` wheel.
//
// `accel` checks that the models are the generator's: the benchmark writes a state in the
// generator's coordinates and gets the accelerations back in them. On a free-flyer base the
// input is the position X, Y, Z, the ZYX angles psi, theta, phi (R = Rz Ry Rx), the joint
// angles; then the world translation rates, the body-frame angular velocity, the joint rates;
// then the joints' torques. The output is the world translation accelerations, the body-frame
// angular acceleration, the joint accelerations. Otherwise (the pendulum) the input is
// Pinocchio's q, v and tau and the output its ddq.

#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/cholesky.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/joint-configuration.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/serialization.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

using namespace pinocchio;
using Eigen::Vector3d;

// The inertia about the centre of mass; products of inertia as the models write them (the
// paper's Eq. 75), so the tensor holds them negated.
static Inertia body(double mass, const Vector3d & com, double ixx, double iyy, double izz, double ixy = 0, double ixz = 0, double iyz = 0) {
  Symmetric3 inertia(ixx, -ixy, iyy, -ixz, -iyz, izz);
  return Inertia(mass, com, inertia);
}

static SE3 at(double x, double y, double z) {
  return SE3(Eigen::Matrix3d::Identity(), Vector3d(x, y, z));
}

// Scene 2 (models/three_body.ron): a middle body free in space, two outer bodies on revolute
// joints about its z and y axes at (+a, 0, 0) and (-a, 0, 0).
static Model three_body() {
  Model m;
  m.gravity.setZero();
  JointIndex base = m.addJoint(0, JointModelFreeFlyer(), SE3::Identity(), "middle");
  m.appendBodyToJoint(base, body(10.0, Vector3d::Zero(), 1.2, 1.5, 1.8, 0.05, 0.03, 0.02));
  JointIndex j1 = m.addJoint(base, JointModelRZ(), at(0.5, 0, 0), "gamma1");
  m.appendBodyToJoint(j1, body(2.0, Vector3d(0.4, 0, 0), 0.02, 0.12, 0.12));
  JointIndex j2 = m.addJoint(base, JointModelRY(), at(-0.5, 0, 0), "gamma2");
  m.appendBodyToJoint(j2, body(2.0, Vector3d(-0.4, 0, 0), 0.02, 0.12, 0.12));
  return m;
}

// Scene 3 (models/satellite_boom.ron): a satellite free in space, a point mass sliding on its
// x axis from l/2.
static Model satellite_boom() {
  Model m;
  m.gravity.setZero();
  JointIndex base = m.addJoint(0, JointModelFreeFlyer(), SE3::Identity(), "satellite");
  m.appendBodyToJoint(base, body(2000.0, Vector3d::Zero(), 1400.0, 900.0, 1100.0, 5.0, 8.0, 3.0));
  JointIndex rho = m.addJoint(base, JointModelPX(), at(1.25, 0, 0), "rho");
  m.appendBodyToJoint(rho, body(1.0, Vector3d::Zero(), 0, 0, 0));
  return m;
}

// generator::model::examples::n_link_pendulum_on_cart(n): a cart on x, n point masses on
// massless links of length 1 about z, gravity along -y.
static Model pendulum_on_cart(int n) {
  Model m;
  m.gravity.linear(Vector3d(0, -9.81, 0));
  JointIndex parent = m.addJoint(0, JointModelPX(), SE3::Identity(), "q0");
  m.appendBodyToJoint(parent, body(1.0, Vector3d::Zero(), 0, 0, 0));
  for (int i = 0; i < n; ++i) {
    parent = m.addJoint(parent, JointModelRZ(), i == 0 ? SE3::Identity() : at(0, 1.0, 0), "q" + std::to_string(i + 1));
    m.appendBodyToJoint(parent, body(1.0, Vector3d(0, 1.0, 0), 0, 0, 0));
  }
  return m;
}

// generator::model::examples::floating_chain(n): a base free in space and n links on revolute
// joints alternating between the parent's z and y axes, no gravity.
static Model floating_chain(int n) {
  Model m;
  m.gravity.setZero();
  JointIndex parent = m.addJoint(0, JointModelFreeFlyer(), SE3::Identity(), "base");
  m.appendBodyToJoint(parent, body(10.0, Vector3d::Zero(), 1.2, 1.5, 1.8));
  for (int i = 1; i <= n; ++i) {
    SE3 place = at(i == 1 ? 0.5 : 0.8, 0, 0);
    std::string name = "a" + std::to_string(i);
    parent = i % 2 == 1 ? m.addJoint(parent, JointModelRZ(), place, name) : m.addJoint(parent, JointModelRY(), place, name);
    m.appendBodyToJoint(parent, body(1.0, Vector3d(0.4, 0, 0), 0.01, 0.06, 0.06));
  }
  return m;
}

// The `accel` mode (above): reads the state, runs ABA once, prints the accelerations.
static int accelerations(const Model & model, Data & data) {
  bool floating = model.joints[1].shortname() == "JointModelFreeFlyer";
  int joints = floating ? model.nv - 6 : model.nv;
  auto read = [](int count) {
    Eigen::VectorXd x(count);
    for (int i = 0; i < count; ++i)
      if (std::scanf("%lf", &x[i]) != 1) std::exit(3);
    return x;
  };
  Eigen::VectorXd q(model.nq), v(model.nv), tau = Eigen::VectorXd::Zero(model.nv);
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  if (floating) {
    Eigen::VectorXd position = read(6);
    rotation = (Eigen::AngleAxisd(position[3], Vector3d::UnitZ()) * Eigen::AngleAxisd(position[4], Vector3d::UnitY()) *
                Eigen::AngleAxisd(position[5], Vector3d::UnitX())).toRotationMatrix();
    Eigen::Quaterniond turn(rotation);
    q.head<3>() = position.head<3>();
    q.segment<4>(3) = turn.coeffs();
    q.tail(joints) = read(joints);
    Eigen::VectorXd rates = read(6);
    v.head<3>() = rotation.transpose() * rates.head<3>();
    v.segment<3>(3) = rates.tail<3>();
    v.tail(joints) = read(joints);
  } else {
    q = read(model.nq);
    v = read(model.nv);
  }
  tau.tail(joints) = read(joints);
  aba(model, data, q, v, tau);
  Eigen::VectorXd out = data.ddq;
  if (floating) {
    // The free flyer's ddq is the derivative of its body-frame velocity: the world
    // translation acceleration is R (a + omega x v).
    Vector3d linear = v.head<3>(), angular = v.segment<3>(3);
    out.head<3>() = rotation * (data.ddq.head<3>() + angular.cross(linear));
  }
  for (int i = 0; i < model.nv; ++i) std::printf("%.17g\n", out[i]);
  return 0;
}

// The best, over 7 rounds, of the mean time of 200 calls of `call`.
template<typename Call> static double best_ns(Call call) {
  double best = 1e300;
  for (int round = 0; round < 7; ++round) {
    auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < 200; ++i) call();
    double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count() / 200.0;
    best = ns < best ? ns : best;
  }
  return best;
}

static Model saved(const std::string & file) {
  Model model;
  model.loadFromText(file);
  return model;
}

// Forward dynamics by the composite-rigid-body algorithm: M from CRBA, the nonlinear effects
// b from RNEA, then M a = tau - b by Pinocchio's Cholesky on the tree's sparsity.
static const Eigen::VectorXd & crba_forward(const Model & model, Data & data, const Eigen::VectorXd & q, const Eigen::VectorXd & v, const Eigen::VectorXd & tau) {
  crba(model, data, q, Convention::WORLD);
  nonLinearEffects(model, data, q, v);
  data.ddq = tau - data.nle;
  cholesky::decompose(model, data);
  cholesky::solve(model, data, data.ddq);
  return data.ddq;
}

// A robot (`aba saved MODEL [MODE]`): `layout` prints each joint's place in q and v; `accel`
// reads q and v, applies the joints' damping (tau = -damping v) and prints ABA's
// accelerations; no mode times ABA and CRBA with Cholesky at a state drawn from a fixed seed.
static int saved_robot(const std::string & file, const std::string & mode) {
  Model model = saved(file);
  Data data(model);
  if (mode == "layout") {
    std::printf("nq %d\nnv %d\n", int(model.nq), int(model.nv));
    for (JointIndex j = 1; j < JointIndex(model.njoints); ++j)
      std::printf("joint %s %d %d %d %d %s\n", model.names[j].c_str(), int(model.joints[j].idx_q()), int(model.joints[j].nq()), int(model.joints[j].idx_v()),
                  int(model.joints[j].nv()), model.joints[j].shortname().c_str());
    return 0;
  }
  if (mode == "accel") {
    Eigen::VectorXd q(model.nq), v(model.nv);
    for (int i = 0; i < model.nq; ++i)
      if (std::scanf("%lf", &q[i]) != 1) return 3;
    for (int i = 0; i < model.nv; ++i)
      if (std::scanf("%lf", &v[i]) != 1) return 3;
    Eigen::VectorXd tau = -model.damping.cwiseProduct(v);
    aba(model, data, q, v, tau);
    for (int i = 0; i < model.nv; ++i) std::printf("%.17g\n", data.ddq[i]);
    return 0;
  }
  std::srand(1);
  Eigen::VectorXd q = randomConfiguration(model, -Eigen::VectorXd::Ones(model.nq), Eigen::VectorXd::Ones(model.nq));
  Eigen::VectorXd v = Eigen::VectorXd::Random(model.nv), tau = Eigen::VectorXd::Zero(model.nv);
  double sink = 0;
  double aba_ns = best_ns([&] {
    aba(model, data, q, v, tau);
    sink += data.ddq[0];
  });
  double crba_ns = best_ns([&] { sink += crba_forward(model, data, q, v, tau)[0]; });
  if (!(sink == sink)) return 1;
  std::printf("aba %.1f\ncrba %.1f\ndof %d\n", aba_ns, crba_ns, int(model.nv));
  return 0;
}

int main(int argc, char ** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: aba MODEL [N]\n");
    return 2;
  }
  std::string which = argv[1];
  if (which == "saved") {
    if (argc < 3) {
      std::fprintf(stderr, "usage: aba saved MODEL [layout|accel]\n");
      return 2;
    }
    return saved_robot(argv[2], argc > 3 ? argv[3] : "");
  }
  int n = argc > 2 ? std::atoi(argv[2]) : 0;
  Model model;
  if (which == "three_body") model = three_body();
  else if (which == "satellite_boom") model = satellite_boom();
  else if (which == "pendulum_on_cart") model = pendulum_on_cart(n);
  else if (which == "floating_chain") model = floating_chain(n);
  else {
    std::fprintf(stderr, "unknown model %s\n", which.c_str());
    return 2;
  }
  Data data(model);
  if (argc > 3 && std::string(argv[3]) == "accel") return accelerations(model, data);
  // A generic state: a random configuration and velocity from a fixed seed, no torques.
  std::srand(1);
  Eigen::VectorXd q = randomConfiguration(model, -Eigen::VectorXd::Ones(model.nq), Eigen::VectorXd::Ones(model.nq));
  Eigen::VectorXd v = Eigen::VectorXd::Random(model.nv);
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(model.nv);
  double best = 1e300, sink = 0;
  for (int round = 0; round < 7; ++round) {
    auto start = std::chrono::steady_clock::now();
    for (int call = 0; call < 200; ++call) {
      aba(model, data, q, v, tau);
      sink += data.ddq[0];
    }
    double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count() / 200.0;
    best = ns < best ? ns : best;
  }
  if (!(sink == sink)) return 1;
  std::printf("aba %.1f\n", best);
  std::printf("dof %d\n", int(model.nv));
  return 0;
}
