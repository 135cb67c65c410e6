//! Approximate visibility (METHOD §7): variance shadow maps from the lights. The exact
//! visibility (shadow rays through the BVH) stays the oracle they are measured against.

pub mod vsm;
