//! A model carried through a room lit by light probes: what the viewer and `hprt report
//! --path` share. The model and the room are baked apart (`runtime::render::with_objects_alone`),
//! so moving the model keeps both bakes; at each position the local map at the model's centre
//! is fused from the probes (`runtime::ProbeLighting`), decomposed with its lights followed
//! from the previous position, and lights the frame: the model through its own transfer, the
//! room's change through the lights' shadow maps and through the model's soft shadow and
//! bounce on the room's SH light (`runtime::RoomShadow`, traced at each position). A turned
//! model keeps its bake turned with it (it was baked alone, so nothing else's shadow turns
//! with it).

use crate::bake::cached_bake;
use crate::error::{ReportError, Result};
use crate::observer::Observer;
use foundation::bvh::SceneBvh;
use foundation::envmap::EnvMap;
use foundation::probe::Probe;
use foundation::scene::{ModelPath, ObjectRole, Pose, Scene, SceneMesh};
use foundation::sh::rotation::ShRotation;
use glam::{Mat3, Quat, Vec3};
use precompute::bake::Transfer;
use runtime::render::{FrameLighting, RenderMode, Renderer, rows_of, with_objects_alone};
use runtime::{DecomposeSettings, ProbeFrame, ProbeLighting, RoomShadow, TrackingSettings};
use std::borrow::Cow;

/// A scene's room (its proxies and probes) and the model (its objects) that moves through it.
pub struct RoomModel {
    /// The scene's geometry, the objects where the scene places them.
    pub geometry: SceneMesh,
    /// Each part's own bake on its vertices of `geometry`.
    pub transfer: Transfer,
    /// The room alone (the composite's proxies without the objects).
    pub room_transfer: Transfer,
    pub lighting: ProbeLighting,
    /// Centre of the objects' bounds where the scene places them.
    pub centre: Vec3,
    /// The scene's `[path]`, if any.
    pub path: Option<ModelPath>,
    /// The room's vertices that take the model's soft shadow and bounce.
    shadow: RoomShadow,
    /// Whether the room takes them (the lights' shadows it always takes).
    pub soft_shadow: bool,
}

/// The model at a pose: the scene's geometry with it there, and the bake turned with it.
pub struct PosedModel {
    pub pose: Pose,
    pub geometry: SceneMesh,
    /// The bake turned with the model; `None` when it is not turned.
    turned: Option<Transfer>,
}

impl RoomModel {
    /// The room and model of `scene`, its probes loaded (their distances traced where not
    /// given), lit under `sky` (the scene's map, turned by its rotation); both parts baked
    /// with the scene's `[bake]` settings, or taken from the cache.
    pub fn open(
        scene: &Scene,
        sky: EnvMap,
        settings: DecomposeSettings,
        observer: &dyn Observer,
    ) -> Result<Self> {
        if scene.probes.is_empty() {
            return Err(ReportError::NoProbes(scene.path.clone()));
        }
        let bake = |scene: &Scene, what: &'static str| {
            cached_bake(scene, observer).map_err(|e| ReportError::Bake {
                what,
                source: Box::new(e),
            })
        };
        let part = |role: ObjectRole, suffix: &str| scene.of_role(role).renamed(suffix);
        let (model, room) = (
            part(ObjectRole::Object, "model"),
            part(ObjectRole::Proxy, "room"),
        );
        let centre = (model.geometry.mesh.bounds())
            .map(|(lo, hi)| 0.5 * (lo + hi))
            .ok_or(ReportError::NoObjects)?;
        let (_, model_transfer) = bake(&model, "the model alone")?;
        // The room without the model, baked with the model's vertices kept (collapsed to a
        // point no ray meets), so that its rows sit on the scene's vertices; the room renderer
        // draws the same rows, so the composite's ratio is one but for the model's shadows.
        let mut collapsed = scene.geometry.clone();
        collapsed.collapse_objects(centre);
        let empty = scene.with_geometry(collapsed).renamed("room");
        let (_, empty) = bake(&empty, "the room alone")?;
        let transfer = with_objects_alone(&scene.geometry, &empty, &model_transfer)?;
        let room_transfer = rows_of(&scene.geometry, ObjectRole::Proxy, &empty)?;
        let proxies = SceneBvh::build(&room.geometry.mesh);
        let probes: Vec<Probe> = (scene.probes.iter())
            .map(|p| p.load(&proxies))
            .collect::<Result<_, _>>()?;
        warn_of_mixed_sizes(scene, &probes);
        let lighting = ProbeLighting::new(probes, proxies, sky, settings, tracking())?;
        Ok(Self {
            shadow: RoomShadow::new(
                &scene.geometry,
                centre,
                runtime::ROOM_SHADOW_RAYS,
                scene.bake.order,
            ),
            soft_shadow: true,
            geometry: scene.geometry.clone(),
            transfer,
            room_transfer,
            lighting,
            centre,
            path: scene.model_path.clone(),
        })
    }

    /// The scene's geometry with the objects at `pose`, and the bake turned with them.
    pub fn posed(&self, pose: Pose) -> Result<PosedModel> {
        let mut geometry = self.geometry.clone();
        geometry.pose_objects(self.centre, pose);
        let turned = match pose.is_turned() {
            true => Some(self.turned_transfer(pose.rotation)?),
            false => None,
        };
        Ok(PosedModel {
            pose,
            geometry,
            turned,
        })
    }

    /// [`Self::transfer`] with the model's rows turned by `rotation`.
    fn turned_transfer(&self, rotation: Quat) -> Result<Transfer> {
        let mut transfer = self.transfer.clone();
        let turn = ShRotation::new(
            Mat3::from_quat(rotation.normalize()),
            transfer.settings.order,
        )?;
        let objects = self.geometry.objects.iter();
        for o in objects.filter(|o| o.role == ObjectRole::Object) {
            let range = o.vertices.start as usize..o.vertices.end as usize;
            transfer.direct.rotate_vertices(range.clone(), &turn);
            transfer.indirect.rotate_vertices(range, &turn);
        }
        Ok(transfer)
    }

    /// Draws `posed` in `renderer` (made with [`Self::geometry`] and [`Self::transfer`]) under
    /// `lighting`: the model's vertices where it is, its bake turned, and the room's rows
    /// scaled by the model's soft shadow and bounce under this lighting. Returns what the
    /// soft shadow cost, in milliseconds.
    pub fn draw(
        &self,
        renderer: &mut Renderer,
        posed: &PosedModel,
        lighting: &FrameLighting,
    ) -> Result<f64> {
        renderer.move_vertices(&posed.geometry)?;
        // Copied only to be scaled by the soft shadow.
        let mut transfer = Cow::Borrowed(posed.turned.as_ref().unwrap_or(&self.transfer));
        let start = std::time::Instant::now();
        if self.soft_shadow {
            let radiance = runtime::model_radiance(&posed.geometry, &transfer, lighting);
            let factors = self.shadow.factors(posed.pose, &lighting.sh, &radiance);
            let scaled = transfer.to_mut();
            for (v, factor) in factors {
                scaled.direct.scale_vertex(v, factor);
                scaled.indirect.scale_vertex(v, factor);
            }
        }
        let shadow_ms = start.elapsed().as_secs_f64() * 1e3;
        renderer.set_transfer(&posed.geometry, &transfer)?;
        renderer.set_lighting(lighting)?;
        Ok(shadow_ms)
    }

    /// The lighting at `centre`, followed from the previous update's, and the renderer's
    /// lighting from it: the hybrid's, the lights' bounce light included as the decomposition
    /// mode says.
    pub fn update(&mut self, centre: Vec3) -> (FrameLighting, ProbeFrame) {
        let frame = self.lighting.update(centre);
        let indirect = runtime::lights_indirect_default(self.lighting.settings().mode);
        let lighting = FrameLighting::for_mode(
            RenderMode::Hybrid,
            &frame.lighting.sh,
            &frame.lighting,
            indirect,
        );
        (lighting, frame)
    }
}

/// Warns when the probes' images differ in size: each is still looked up at its own
/// resolution, but the sharper ones' detail comes and goes as the point moves between them.
pub fn warn_of_mixed_sizes(scene: &Scene, probes: &[Probe]) {
    let size = |p: &Probe| (p.radiance.width(), p.radiance.height());
    let name = |k: usize| scene.probes.get(k).map_or("?", |p| p.name.as_str());
    if let Some(first) = probes.first()
        && let Some(k) = (1..probes.len()).find(|k| size(&probes[*k]) != size(first))
    {
        let ((w0, h0), (w1, h1)) = (size(first), size(&probes[k]));
        log::warn!(
            "{}: the probes' images differ in size ({w0}×{h0} for {:?}, {w1}×{h1} for {:?}): \
             each is looked up at its own resolution, so detail comes and goes as the model \
             moves between them",
            scene.path.display(),
            name(0),
            name(k)
        );
    }
}

/// How the lights are followed as the model moves: the environment sequences' rules.
fn tracking() -> TrackingSettings {
    TrackingSettings::default()
}

#[cfg(test)]
mod tests {
    use super::*;
    use foundation::Rgb;
    use foundation::mesh::{box_mesh, sphere_mesh};
    use precompute::bake::BakeSettings;

    /// The room baked with the model collapsed gives each room vertex the samples it gets in a
    /// bake with the model: where no sample meets the model (a box face turned away from it)
    /// the two bakes agree bit for bit, so the composite's ratio is exactly one there.
    #[test]
    fn a_collapsed_model_leaves_the_rooms_samples_as_they_were() {
        let mut geometry = SceneMesh::default();
        let sphere = sphere_mesh(Vec3::new(0.0, 1.0, 0.0), 1.0, 2);
        geometry.push_object("model".into(), &sphere, Rgb::splat(0.7));
        let block = box_mesh(
            Vec3::new(5.0, 0.0, -1.0),
            Vec3::new(6.0, 2.0, 1.0),
            [2; 3],
            [false; 6],
        );
        geometry.push_object("block".into(), &block, Rgb::splat(0.5));
        geometry.objects[1].role = ObjectRole::Proxy;
        let settings = BakeSettings {
            order: 3,
            samples: 64,
            bounces: 0,
            seed: 3,
        };
        let bake = |g: &SceneMesh| {
            let bvh = SceneBvh::build(&g.mesh);
            let no_progress = &foundation::infra::progress::NoProgress;
            precompute::bake::bake(g, &bvh, &settings, no_progress)
                .unwrap()
                .0
        };
        let mut collapsed = geometry.clone();
        collapsed.collapse_objects(Vec3::new(0.0, 1.0, 0.0));
        let (with, without) = (bake(&geometry), bake(&collapsed));
        let block = &geometry.objects[1];
        let (mut away, mut facing_changed) = (0, 0);
        for v in block.vertices.start as usize..block.vertices.end as usize {
            let same = (0..3).all(|c| with.direct.vector(v, c) == without.direct.vector(v, c));
            if geometry.mesh.normals[v].x > 0.5 {
                assert!(same, "vertex {v}, turned away from the model, changed");
                away += 1;
            }
            facing_changed += usize::from(geometry.mesh.normals[v].x < -0.5 && !same);
        }
        assert!(away > 4, "{away}");
        assert!(facing_changed > 0, "the face toward the model sees it");
    }
}
