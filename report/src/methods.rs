//! The methods the reports compare, in one place: what a method is called, how it makes a
//! frame's lighting from a map, and which report families measure it. A new peer is one entry
//! of [`PEERS`]: every family that lists it renders it, names it and keys its results by it.

use crate::error::Result;
use foundation::envmap::EnvMap;
use runtime::render::{FrameLighting, RenderMode};
use runtime::{DecomposeMode, DecomposeSettings, EnvironmentLighting, TrackingSettings};

/// How a method makes a frame's lighting from the map it is given.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Technique {
    /// The SH projection of the whole map (the thesis' baseline).
    Prt,
    /// SH part + shadow-mapped lights from a decomposition in `mode`; `tracked`: the lights
    /// are followed from frame to frame (hysteresis, fades) rather than found afresh.
    Hybrid { mode: DecomposeMode, tracked: bool },
    /// Median-cut lights (a power of two), shadow-mapped, nothing else.
    MedianCut(usize),
    /// One shadowed light plus unshadowed order-3 SH irradiance.
    ShSun,
    /// Order-3 SH irradiance by the normal and the prefiltered map, nothing shadowed.
    Ibl,
}

impl Technique {
    /// How the renderer draws the technique's lighting.
    pub fn render_mode(self) -> RenderMode {
        match self {
            Technique::Prt => RenderMode::Prt,
            Technique::Hybrid { .. } => RenderMode::Hybrid,
            Technique::MedianCut(_) => RenderMode::MedianCut,
            Technique::ShSun => RenderMode::ShSun,
            Technique::Ibl => RenderMode::Ibl,
        }
    }

    /// Whether the lighting depends on the Weber threshold (the threshold sweep's methods).
    pub fn is_hybrid(self) -> bool {
        matches!(self, Technique::Hybrid { .. })
    }

    /// The decomposition settings of SH order `order` at Weber `threshold`: the hybrid's mode,
    /// the consistent mode for the others.
    fn decompose_settings(self, order: usize, threshold: f32) -> DecomposeSettings {
        let mode = match self {
            Technique::Hybrid { mode, .. } => mode,
            _ => DecomposeMode::Consistent,
        };
        DecomposeSettings {
            threshold,
            ..DecomposeSettings::for_mode(mode, order)
        }
    }

    /// Sets `lighting` up for the technique (a no-op when it already is): the decomposition of
    /// SH order `order` at Weber `threshold`, or the peers' light count.
    pub(crate) fn configure(
        self,
        lighting: &mut EnvironmentLighting,
        order: usize,
        threshold: f32,
    ) -> Result<()> {
        match self {
            Technique::MedianCut(count) => lighting.set_median_cut_lights(count)?,
            Technique::ShSun => lighting.set_median_cut_lights(1)?,
            Technique::Prt | Technique::Ibl | Technique::Hybrid { .. } => {
                lighting.set_settings(self.decompose_settings(order, threshold))?
            }
        }
        Ok(())
    }

    /// A lighting of `map` for the technique, lights tracked where it tracks them, at the
    /// mode's own Weber threshold, turned by `rotation_deg`.
    pub(crate) fn start(
        self,
        map: &EnvMap,
        order: usize,
        rotation_deg: f32,
    ) -> Result<EnvironmentLighting> {
        let settings = DecomposeSettings::for_mode(DecomposeMode::Consistent, order);
        let mut lighting = EnvironmentLighting::new(map, settings.clone())?;
        if let Technique::Hybrid { tracked: true, .. } = self {
            lighting.enable_tracking(Some(TrackingSettings::default()))?;
        }
        self.configure(&mut lighting, order, settings.threshold)?;
        lighting.set_rotation(rotation_deg);
        Ok(lighting)
    }

    /// The lighting of the map `lighting` holds, set up by [`Technique::configure`] or
    /// [`Technique::start`]: the frame's lighting, its number of lights and what making it
    /// cost (milliseconds).
    pub(crate) fn frame(self, lighting: &mut EnvironmentLighting) -> (FrameLighting, usize, f64) {
        let frame = lighting.frame(self.render_mode(), None);
        let lights = frame.lighting.lights.len();
        (frame.lighting, lights, frame.ms)
    }
}

/// A method of a report: its name in tables, its name in file names, and its technique.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Method {
    pub name: &'static str,
    pub file_stem: &'static str,
    pub technique: Technique,
}

impl Method {
    const fn new(name: &'static str, file_stem: &'static str, technique: Technique) -> Self {
        Self {
            name,
            file_stem,
            technique,
        }
    }

    /// Whether the method depends on the Weber threshold (the sweep's methods).
    pub fn is_hybrid(self) -> bool {
        self.technique.is_hybrid()
    }
}

/// Which map a method of the path report lights the model with, at each position.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathMap {
    /// The map of the probe nearest the room's centre, everywhere: what a single capture gives.
    OneProbe,
    /// The map of the probe nearest the model.
    NearestProbe,
    /// The local map fused from every probe at the model's centre (the fusion thesis).
    Fused,
    /// The true probe, path-traced at the model's centre: the best a distant-light method can
    /// do.
    TrueProbe,
}

/// A method of the path report: a method and the map it is given.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PathMethod {
    pub method: Method,
    pub map: PathMap,
}

/// Where a peer appears besides the report per map (and the composite report), which measure
/// every peer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PeerFamilies {
    /// In the sequence report, on every frame's map.
    pub sequence: bool,
    /// In the path report, on the fused map, under this name.
    pub path: Option<&'static str>,
}

/// A peer: a method users would pick instead of the hybrid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Peer {
    pub method: Method,
    pub families: PeerFamilies,
}

/// The peers, in the tables' order.
pub const PEERS: [Peer; 4] = [
    Peer {
        method: Method::new("median-cut/8", "median-cut-8", Technique::MedianCut(8)),
        families: PeerFamilies {
            sequence: false,
            path: None,
        },
    },
    Peer {
        method: Method::new("median-cut/32", "median-cut-32", Technique::MedianCut(32)),
        // The fusion thesis' own choice, on its own fused map.
        families: PeerFamilies {
            sequence: false,
            path: Some("median cut (fused)"),
        },
    },
    Peer {
        method: Method::new("sh-sun", "sh-sun", Technique::ShSun),
        families: PeerFamilies {
            sequence: false,
            path: None,
        },
    },
    // What Filament, three.js and Bevy draw.
    Peer {
        method: Method::new("ibl", "ibl", Technique::Ibl),
        families: PeerFamilies {
            sequence: false,
            path: None,
        },
    },
];

const PRT: Method = Method::new("prt", "prt", Technique::Prt);

/// The hybrid tracked from frame to frame in the consistent mode (sequences and paths).
pub(crate) const TRACKED: Technique = Technique::Hybrid {
    mode: DecomposeMode::Consistent,
    tracked: true,
};

/// The report per map's methods, in its table's order: PRT, the hybrid in both decomposition
/// modes, then the peers.
pub fn per_map_methods() -> Vec<Method> {
    let hybrid = |mode| Technique::Hybrid {
        mode,
        tracked: false,
    };
    let own = [
        PRT,
        Method::new(
            "hybrid/thesis",
            "hybrid-thesis",
            hybrid(DecomposeMode::Thesis),
        ),
        Method::new(
            "hybrid/consistent",
            "hybrid-consistent",
            hybrid(DecomposeMode::Consistent),
        ),
    ];
    own.into_iter()
        .chain(PEERS.iter().map(|p| p.method))
        .collect()
}

/// The sequence report's methods: PRT, the hybrid tracked and decomposed afresh each frame,
/// then the peers it lists.
pub fn sequence_methods() -> Vec<Method> {
    let untracked = Technique::Hybrid {
        mode: DecomposeMode::Consistent,
        tracked: false,
    };
    let own = [
        PRT,
        Method::new("hybrid/tracked", "hybrid-tracked", TRACKED),
        Method::new("hybrid/untracked", "hybrid-untracked", untracked),
    ];
    let peers = PEERS.iter().filter(|p| p.families.sequence);
    own.into_iter().chain(peers.map(|p| p.method)).collect()
}

/// The path report's methods: the tracked hybrid on each map, then the peers it lists on the
/// fused map.
pub fn path_methods() -> Vec<PathMethod> {
    let hybrid = |name, file_stem, map| PathMethod {
        method: Method::new(name, file_stem, TRACKED),
        map,
    };
    let own = [
        hybrid("one probe", "one-probe", PathMap::OneProbe),
        hybrid("nearest probe", "nearest-probe", PathMap::NearestProbe),
        hybrid("fused", "fused", PathMap::Fused),
        hybrid("true probe", "true-probe", PathMap::TrueProbe),
    ];
    let peers = PEERS.iter().filter_map(|p| {
        let name = p.families.path?;
        let method = Method { name, ..p.method };
        Some(PathMethod {
            method,
            map: PathMap::Fused,
        })
    });
    own.into_iter().chain(peers).collect()
}

/// The entry of `results` made by the method called `name` (results carry their method's name).
pub(crate) fn result_of<'a, T>(
    results: &'a [T],
    name: &str,
    method_of: impl Fn(&T) -> &str,
) -> Option<&'a T> {
    results.iter().find(|r| method_of(r) == name)
}

/// Each named method's values over the rows (frames, positions) of a report, for a plot: a row's
/// value is `value` of that method's result there, NaN where there is none.
pub(crate) fn series_by_method<'a, R: 'a>(
    names: impl Iterator<Item = &'a str>,
    rows: &[&'a [R]],
    method_of: impl Fn(&R) -> &str + Copy,
    value: &dyn Fn(&R) -> Option<f64>,
) -> Vec<(String, Vec<f64>)> {
    names
        .map(|name| {
            let values = (rows.iter())
                .map(|row| (result_of(row, name, method_of).and_then(value)).unwrap_or(f64::NAN))
                .collect();
            (name.to_owned(), values)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_family_names_its_methods_once() {
        let names = |methods: Vec<Method>| methods.iter().map(|m| m.name).collect::<Vec<_>>();
        let path: Vec<Method> = path_methods().iter().map(|m| m.method).collect();
        for family in [per_map_methods(), sequence_methods(), path] {
            let all = names(family.clone());
            for (k, name) in all.iter().enumerate() {
                assert!(!all[..k].contains(name), "{name} twice in {all:?}");
            }
            let stems: Vec<_> = family.iter().map(|m| m.file_stem).collect();
            for (k, stem) in stems.iter().enumerate() {
                assert!(!stems[..k].contains(stem), "{stem} twice");
                assert!(stem.chars().all(|c| c.is_ascii_alphanumeric() || c == '-'));
            }
        }
    }

    #[test]
    fn every_peer_is_in_the_report_per_map_after_the_thesis_methods() {
        let methods = per_map_methods();
        assert_eq!(&methods[3..], PEERS.map(|p| p.method));
        assert!(methods[1..3].iter().all(|m| m.is_hybrid()));
        assert!(!methods[0].is_hybrid() && methods[3..].iter().all(|m| !m.is_hybrid()));
    }

    #[test]
    fn peers_join_the_families_they_list() {
        let sequence = sequence_methods();
        let path = path_methods();
        for peer in PEERS {
            let in_sequence = sequence.contains(&peer.method);
            assert_eq!(in_sequence, peer.families.sequence, "{}", peer.method.name);
            let on_path = path
                .iter()
                .find(|m| m.method.technique == peer.method.technique);
            assert_eq!(on_path.map(|m| m.method.name), peer.families.path);
            assert!(on_path.is_none_or(|m| m.map == PathMap::Fused));
        }
    }

    #[test]
    fn results_are_found_by_their_method() {
        let results = [("prt", 1), ("sh-sun", 2)];
        assert_eq!(result_of(&results, "sh-sun", |r| r.0), Some(&("sh-sun", 2)));
        assert_eq!(result_of(&results, "fused", |r| r.0), None);
    }
}
