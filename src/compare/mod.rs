//! Error metrics between images and false-colour error maps.
