//! ROS 2 on the wire, as skillc speaks it: CDR ([`cdr`]), the few message types skillc reads and
//! writes ([`msgs`]), their REP 2011 type hashes ([`hash`]) and the names, attachments and
//! liveliness tokens of `rmw_zenoh` ([`rmw`]), and ROS 2 bags ([`bag`]: demonstrations read from
//! MCAP files, run logs written as MCAP; the `mcap` feature). The Zenoh transport uses the
//! messages alone; nothing here depends on a ROS 2 installation.
#![warn(missing_docs)]

pub mod bag;
pub mod cdr;
pub mod hash;
pub mod msgs;
pub mod rmw;
