//! The demonstration as CSV text, the columns of docs/method.md §1.

use std::fmt::Write as _;

use super::Demonstration;

/// The demonstration as CSV with the columns of docs/method.md §1 (6 decimals: µm, µN).
pub fn to_csv(demo: &Demonstration) -> String {
    let mut out = String::with_capacity(demo.samples.len() * 120);
    out.push_str("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n");
    for sample in &demo.samples {
        let q = sample.orientation.quaternion();
        let _ = writeln!(
            out,
            "{:.4},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.6},{:.4},{:.4},{:.4},{:.5},{:.5},{:.5}",
            sample.t_s,
            sample.position_m.x,
            sample.position_m.y,
            sample.position_m.z,
            q.w,
            q.i,
            q.j,
            q.k,
            sample.force_n.x,
            sample.force_n.y,
            sample.force_n.z,
            sample.torque_nm.x,
            sample.torque_nm.y,
            sample.torque_nm.z,
        );
    }
    out
}
