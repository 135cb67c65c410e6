//! CPU renderers (rayon).
