#include "rgbdtam/core/pose_graph.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

namespace rgbdtam {

Matrix6d graph_information(const Matrix6d& tracker_information, const SE3& T_k_c) {
  // T_k_c exp(xi) = exp(delta) T_k_c with xi = Ad(T_c_k) delta.
  const Matrix6d A = adjoint(T_k_c);
  return A.transpose() * tracker_information * A;
}

Matrix6d information_through(const Matrix6d& info_a_f, const Matrix6d& info_b_f, const SE3& T_b_f) {
  // T_a_f exp(xa) (T_b_f exp(xb))^-1 = T_a_b exp(Ad(T_b_f) (xa - xb)).
  const Matrix6d I = Matrix6d::Identity();
  // A tiny ridge: a direction one measurement leaves free is free in the result too.
  constexpr double kRidge = 1e-9;
  const Matrix6d cov =
      (info_a_f + kRidge * I).ldlt().solve(I) + (info_b_f + kRidge * I).ldlt().solve(I);
  const Matrix6d A = adjoint(T_b_f.inverse());
  return A.transpose() * cov.ldlt().solve(I) * A;
}

Matrix6d information_with_jump(const Matrix6d& information, double jump_m, double jump_rad) {
  const Matrix6d I = Matrix6d::Identity();
  constexpr double kRidge = 1e-9;  // as above: a free direction stays free
  Matrix6d cov = (information + kRidge * I).ldlt().solve(I);
  cov.topLeftCorner<3, 3>().diagonal().array() += jump_m * jump_m;
  cov.bottomRightCorner<3, 3>().diagonal().array() += jump_rad * jump_rad;
  return cov.ldlt().solve(I);
}

void PoseGraph::allocate(int max_nodes, int max_edges) {
  RGBDTAM_ASSERT(max_nodes > 0 && max_edges > 0, "empty pose graph");
  max_nodes_ = max_nodes;
  max_edges_ = max_edges;
  const size_t n = static_cast<size_t>(max_nodes);
  pose_.reset(new SE3[n]);
  edge_.reset(new Edge[static_cast<size_t>(max_edges)]);
  H_diag_.reset(new Matrix6d[n]);
  preconditioner_.reset(new Matrix6d[n]);
  for (auto* v : {&g_, &delta_, &r_, &z_, &p_, &Ap_}) v->reset(new Vector6d[n]);
  clear();
}

int PoseGraph::add_node(const SE3& T_w_n) {
  if (nodes_ == max_nodes_) return -1;
  pose_[nodes_] = T_w_n;
  return nodes_++;
}

bool PoseGraph::add_edge(int from, int to, const SE3& T_from_to, const Matrix6d& information) {
  RGBDTAM_ASSERT(from >= 0 && to >= 0 && from < nodes_ && to < nodes_ && from != to,
                 "pose-graph edge between unknown nodes");
  if (edges_ == max_edges_) return false;
  Edge& e = edge_[edges_++];
  e.from = from;
  e.to = to;
  e.T_from_to = T_from_to;
  e.information = information;
  return true;
}

// e = log(T_from_to^-1 T_w_from^-1 T_w_to): zero when the poses agree with the measurement.
Vector6d PoseGraph::residual(const Edge& e) const {
  return (e.T_from_to.inverse() * pose_[e.from].inverse() * pose_[e.to]).log();
}

double PoseGraph::cost() const {
  double c = 0.0;
  for (int k = 0; k < edges_; ++k) {
    const Vector6d r = residual(edge_[k]);
    c += r.dot(edge_[k].information * r);
  }
  return c;
}

void PoseGraph::build_normal_equations() {
  for (int i = 0; i < nodes_; ++i) {
    H_diag_[i].setZero();
    g_[i].setZero();
  }
  for (int k = 0; k < edges_; ++k) {
    Edge& e = edge_[k];
    const Vector6d r = residual(e);
    // d e / d delta_to = I and d e / d delta_from = -Ad(T_to^-1 T_from), to first order in e.
    const Matrix6d J_from = -adjoint(pose_[e.to].inverse() * pose_[e.from]);
    const Matrix6d JtW = J_from.transpose() * e.information;
    H_diag_[e.from] += JtW * J_from;
    H_diag_[e.to] += e.information;
    e.H_from_to = JtW;
    g_[e.from] += JtW * r;
    g_[e.to] += e.information * r;
  }
}

void PoseGraph::multiply(const Vector6d* x, Vector6d* out) const {
  for (int i = 0; i < nodes_; ++i) out[i] = H_diag_[i] * x[i];
  for (int k = 0; k < edges_; ++k) {
    const Edge& e = edge_[k];
    out[e.from] += e.H_from_to * x[e.to];
    out[e.to] += e.H_from_to.transpose() * x[e.from];
  }
  for (int i = 0; i < std::min(fixed_, nodes_); ++i) out[i].setZero();
}

int PoseGraph::solve(int max_iterations) {
  for (int i = 0; i < nodes_; ++i) {
    delta_[i].setZero();
    r_[i] = -g_[i];
    // Block-Jacobi preconditioner; a tiny ridge keeps an unconstrained direction solvable.
    preconditioner_[i] =
        (H_diag_[i] + 1e-9 * Matrix6d::Identity()).ldlt().solve(Matrix6d::Identity());
  }
  for (int i = 0; i < std::min(fixed_, nodes_); ++i) r_[i].setZero();
  double rz = 0.0, r0 = 0.0;
  for (int i = 0; i < nodes_; ++i) {
    z_[i] = preconditioner_[i] * r_[i];
    p_[i] = z_[i];
    rz += r_[i].dot(z_[i]);
    r0 += r_[i].squaredNorm();
  }
  int it = 0;
  for (; it < max_iterations && rz > 0.0; ++it) {
    multiply(p_.get(), Ap_.get());
    double pAp = 0.0;
    for (int i = 0; i < nodes_; ++i) pAp += p_[i].dot(Ap_[i]);
    if (!(pAp > 0.0)) break;
    const double alpha = rz / pAp;
    double rr = 0.0, rz_next = 0.0;
    for (int i = 0; i < nodes_; ++i) {
      delta_[i] += alpha * p_[i];
      r_[i] -= alpha * Ap_[i];
      rr += r_[i].squaredNorm();
    }
    if (rr <= 1e-20 * r0) {
      ++it;
      break;
    }
    for (int i = 0; i < nodes_; ++i) {
      z_[i] = preconditioner_[i] * r_[i];
      rz_next += r_[i].dot(z_[i]);
    }
    const double beta = rz_next / rz;
    rz = rz_next;
    for (int i = 0; i < nodes_; ++i) p_[i] = z_[i] + beta * p_[i];
  }
  return it;
}

PoseGraphStats PoseGraph::optimize(int max_iterations) {
  PoseGraphStats s;
  s.initial_cost = s.final_cost = cost();
  if (nodes_ < 2 || edges_ == 0) return s;
  const int max_cg = std::max(50, 4 * nodes_);
  for (int it = 0; it < max_iterations; ++it) {
    build_normal_equations();
    s.cg_iterations += solve(max_cg);
    for (int i = fixed_; i < nodes_; ++i) pose_[i] = pose_[i] * SE3::exp(delta_[i]);
    ++s.iterations;
    const double c = cost();
    const double previous = s.final_cost;
    s.final_cost = c;
    if (previous - c <= 1e-6 * previous) break;
  }
  return s;
}

}  // namespace rgbdtam
