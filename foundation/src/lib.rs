//! What every part of hprt stands on: the shared vocabulary of the bake, the decomposition, the
//! renderer, the reference and the report.
//!
//! - values: [`color`], [`camera`], [`sh`] (spherical harmonics and their rotation),
//!   [`sampling`] (warps with their densities), [`material`] (the Phong BSDF);
//! - data: [`envmap`] (environment maps: loading, sampling, cube faces), [`mesh`] (loaders and
//!   shapes), [`texture`], [`image_io`];
//! - the scene file ([`scene`]) and its settings ([`bake_settings`], [`settings`]);
//! - ray casting ([`bvh`]), shared by the bake and the reference;
//! - [`infra`]: atomic files, huge pages, prefetching, progress, named enums.

// Every public item is reachable from the crate root: the API is what lib.rs exports.
#![deny(unreachable_pub)]

#[macro_use]
pub mod infra;

pub mod bake_settings;
pub mod bvh;
pub mod camera;
pub mod color;
pub mod composite;
pub mod envmap;
pub mod image_io;
pub mod material;
pub mod mesh;
pub mod probe;
pub mod sampling;
pub mod scene;
pub mod settings;
pub mod sh;
pub mod texture;

pub use color::{Rgb, luminance};
