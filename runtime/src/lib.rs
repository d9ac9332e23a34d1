//! The per-frame half of hprt.
