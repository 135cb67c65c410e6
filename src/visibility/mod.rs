//! Approximate visibility (METHOD §7): variance shadow maps from the lights (`vsm`) and
//! imperfect shadow maps of virtual point lights (`ism`), and ray-cast visibility maps at the
//! reflector tree's nodes (`node_maps`, what `sg --visibility approx` uses). The exact visibility (shadow rays
//! through the BVH) stays the oracle they are measured against.

pub mod ism;
pub mod vsm;
