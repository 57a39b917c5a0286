//! The adjoint-based hybrid position/force controller (docs/method.md §6, thesis 4.1.4 and 4.2.3).
//!
//! Cartesian impedance with a quaternion orientation error plus PI force control with a
//! saturated integral, combined per axis of a compliant frame by the selection `S` and the
//! stiffness `K`, and moved into the control frame by the full adjoints every tick (frames move):
//!
//! ```text
//! w = Ω e_p − D (ẋ − P ẋ_d − P̃ ẋ_f) + Ω̃ f_d + k_p Ω̃ e_f + k_i Adg sat(∫ S̃ Adg⁻¹ e_f dt)
//! τ = Jᵀ w + g(q) + N (−k_n (q − q_rest) − d_n q̇)
//! ```
//!
//! The **control frame** has its origin at the tool point and the base frame's axes; `J` is the
//! geometric tool Jacobian in that frame. Wrenches are the wrench the ROBOT APPLIES (the negative
//! of the sensor reading, which is what the environment exerts on the tool), taken about the tool
//! point. `e_p = [p_d − p; θ]` with `θ` the rotation vector of `q_d q⁻¹`, `e_f = f_d − f`.
//!
//! Corrections to the thesis text (docs/method.md §6): damping opposes velocity, and gravity `g(q)` is a
//! joint-space term outside `Jᵀ(·)`. Additions: force feed-forward `Ω̃ f_d`, a desired-velocity
//! feed-forward on the position axes (`P = Ad S Ad⁻¹`; with `ẋ_d = 0` the law is exactly the written one),
//! the travel a changing force asks for on the force axes (`P̃ = Ad S̃ Ad⁻¹`, [`travel`]),
//! null-space posture control for the redundant joint, joint-velocity braking and torque limits.
//! The integral is kept in compliant-frame coordinates so that a rotating frame (contour) does
//! not drag a stale integral along; for a fixed frame it equals `sat(∫ Ω̃ e_f dt)`.

pub mod adjoint;
mod law;
pub mod travel;

pub use law::{Command, ControlState, ControllerGains, HybridController};
