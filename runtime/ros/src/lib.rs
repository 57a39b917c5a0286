//! ROS 2 on the wire, as skillc speaks it: CDR ([`cdr`]), the few message types skillc reads and
//! writes ([`msgs`]), their REP 2011 type hashes ([`hash`]) and the names, attachments and
//! liveliness tokens of `rmw_zenoh` ([`rmw`]). Used by the MCAP reader and writer and by the Zenoh
//! transport; it depends on no ROS 2 installation.
#![warn(missing_docs)]

pub mod cdr;
pub mod hash;
pub mod msgs;
pub mod rmw;
