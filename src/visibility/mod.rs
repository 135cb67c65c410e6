//! Approximate visibility (METHOD §7): variance shadow maps from the lights (`vsm`) and
//! imperfect shadow maps of virtual point lights (`ism`). The exact visibility (shadow rays
//! through the BVH) stays the oracle they are measured against.

pub mod ism;
pub mod vsm;
