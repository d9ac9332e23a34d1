//! The offline half of hprt: everything computed on the CPU before a frame is drawn.
//!
//! Data flows one way: a [`scene`] (meshes, camera, environment) is loaded, a [`bvh`] is built
//! over it, the [`bake`] computes per-vertex spherical-harmonic transfer ([`sh`]) and stores it
//! in a [`bakefile`]. The [`reference`] path tracer renders the same scene as ground truth.

pub mod color;
#[macro_use]
pub mod named_enum;
pub mod envmap;
pub mod export;
pub mod image_io;
pub mod material;
pub mod mesh;
pub mod model_scene;
pub mod quadrature;
pub mod reference;
pub mod sampling;
pub mod sh;
pub mod sh_rotation;

pub use color::{Rgb, luminance};
pub mod atomic_file;
pub mod bake;
pub mod bake_settings;
pub mod bakefile;
pub mod bvh;
pub mod camera;
pub mod huge_pages;
pub mod prefetch;
pub mod progress;
pub mod scene;
pub mod settings;
pub mod texture;
