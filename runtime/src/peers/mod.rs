//! The methods a user would weigh against the hybrid, as lighting configurations of the same
//! renderer (its shadow-map and light passes): [`median_cut`] lights alone, and
//! [`sh_sun`], one shadowed light plus unshadowed low-order SH irradiance.

pub(crate) mod median_cut;
pub(crate) mod sh_sun;
