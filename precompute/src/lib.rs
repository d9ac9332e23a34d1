//! The offline bake of hprt (thesis chapter 4): per-vertex spherical-harmonic transfer with
//! shadowing and interreflections, computed on the CPU before a frame is drawn.
//!
//! Data flows one way: a scene ([`foundation::scene`]) is loaded and its [`foundation::bvh`]
//! built, the [`bake`] traces rays from every vertex and sums the Neumann series, and the result
//! is stored in a [`bakefile`].

// Every public item is reachable from the crate root: the API is what lib.rs exports.
#![deny(unreachable_pub)]

pub mod bake;
pub mod bakefile;
pub mod cache;
pub mod shardfile;
