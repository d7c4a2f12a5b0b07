//! Embree 3 wrapper (being written).
