//! The window's events: frames, the window's opening, the mouse and the keyboard.

use super::App;
use super::window::WindowGpu;
use anyhow::Context;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::window::{Window, WindowId};

impl App {
    pub(super) fn frame(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let now = Instant::now();
        if let Some(last) = self.stats.last_frame {
            let dt = now.duration_since(last).as_secs_f64();
            self.stats.frame_ms.push_back(dt * 1e3);
            if self.stats.frame_ms.len() > 60 {
                self.stats.frame_ms.pop_front();
            }
            if self.settings.animate {
                self.settings.rotation_deg = (self.settings.rotation_deg
                    + self.settings.animate_speed * dt as f32)
                    .rem_euclid(360.0);
            }
        }
        self.stats.last_frame = Some(now);
        self.poll_jobs();
        self.run_script(event_loop)?;
        self.ensure_renderer()?;
        self.apply_composite()?;
        if self.window.renderer.is_some() {
            self.advance_sequence()?;
        }
        self.update_lighting()?;
        let camera = self.current_camera();
        if let Some(renderer) = self.window.renderer.as_mut() {
            if renderer.set_camera(&camera)?
                && let Some(gpu) = self.window.gpu.as_mut()
            {
                gpu.renderer_changed();
            }
            renderer.render()?;
        }
        let window = self.window.window.clone().context("no window")?;
        let (paint, screen) = self.run_ui(&window);
        let gpu = self.window.gpu.as_mut().context("no window")?;
        let frame = match gpu.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(frame)
            | wgpu::CurrentSurfaceTexture::Suboptimal(frame) => frame,
            other => {
                log::warn!("skipping a frame: {other:?}");
                let (w, h) = (gpu.config.width, gpu.config.height);
                gpu.resize(w, h);
                return Ok(());
            }
        };
        let view = frame.texture.create_view(&Default::default());
        let mut encoder = gpu.gpu.device.create_command_encoder(&Default::default());
        gpu.record(
            &mut encoder,
            &view,
            self.window.renderer.as_ref(),
            self.settings.exposure,
            &paint,
            &screen,
        );
        gpu.gpu.queue.submit([encoder.finish()]);
        window.pre_present_notify();
        gpu.gpu.queue.present(frame);
        self.stats.frames += 1;
        window.request_redraw();
        Ok(())
    }

    pub(super) fn open_window(&mut self, event_loop: &ActiveEventLoop) -> anyhow::Result<()> {
        let (width, height) = self.window.size;
        let attributes = Window::default_attributes()
            .with_title(format!("hprt — {}", self.scene.name))
            .with_inner_size(winit::dpi::PhysicalSize::new(width, height));
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .context("cannot create a window")?,
        );
        let descriptor = wgpu::InstanceDescriptor::new_with_display_handle(Box::new(
            event_loop.owned_display_handle(),
        ));
        let gpu = WindowGpu::new(window.clone(), self.window.backend, descriptor)?;
        self.stats.adapter = gpu.gpu.description().to_string();
        println!("adapter: {}", self.stats.adapter);
        self.window.egui_state = Some(egui_winit::State::new(
            self.window.egui_ctx.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            None,
        ));
        self.window.gpu = Some(gpu);
        self.window.window = Some(window.clone());
        window.request_redraw();
        Ok(())
    }

    pub(super) fn mouse_moved(&mut self, x: f64, y: f64) {
        let previous = self.input.cursor;
        self.input.cursor = (x, y);
        if let Some((button, _)) = self.input.drag {
            let (dx, dy) = ((x - previous.0) as f32, (y - previous.1) as f32);
            match button {
                MouseButton::Left => self.input.orbit.rotate(dx, dy),
                _ => self.input.orbit.pan(dx, dy, self.window.size.1),
            }
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.window.is_some() {
            return;
        }
        if let Err(e) = self.open_window(event_loop) {
            self.error = Some(e);
            event_loop.exit();
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let consumed = match (&mut self.window.egui_state, &self.window.window) {
            (Some(state), Some(window)) => state.on_window_event(window, &event).consumed,
            _ => false,
        };
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gpu) = self.window.gpu.as_mut() {
                    gpu.resize(size.width, size.height);
                }
                self.window.size = (size.width.max(1), size.height.max(1));
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.frame(event_loop) {
                    self.error = Some(e);
                    event_loop.exit();
                }
            }
            WindowEvent::CursorMoved { position, .. } => self.mouse_moved(position.x, position.y),
            WindowEvent::MouseInput { state, button, .. } if !consumed => match state {
                ElementState::Pressed => self.input.drag = Some((button, self.input.cursor)),
                ElementState::Released => self.input.drag = None,
            },
            WindowEvent::MouseInput {
                state: ElementState::Released,
                ..
            } => self.input.drag = None,
            WindowEvent::MouseWheel { delta, .. } if !consumed => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                self.input.orbit.zoom(steps);
            }
            WindowEvent::KeyboardInput { event, .. }
                if !consumed
                    && event.state == ElementState::Pressed
                    && event.logical_key == winit::keyboard::Key::Character("r".into()) =>
            {
                self.reset_view();
            }
            WindowEvent::KeyboardInput { event, .. }
                if !consumed && event.state == ElementState::Pressed =>
            {
                if let Some(offset) = model_step(&event.logical_key) {
                    self.settings.play_path = false;
                    self.move_model(offset);
                }
                if let Some(degrees) = model_turn(&event.logical_key) {
                    self.settings.play_path = false;
                    self.turn_model(degrees);
                }
            }
            _ => {}
        }
    }
}

/// How far a key moves a room's model: the arrows along the floor (x, z), Page Up and Down
/// up and down, by `MODEL_STEP`.
fn model_step(key: &winit::keyboard::Key) -> Option<glam::Vec3> {
    use winit::keyboard::{Key, NamedKey};
    let Key::Named(named) = key else { return None };
    let direction = match named {
        NamedKey::ArrowLeft => glam::Vec3::NEG_X,
        NamedKey::ArrowRight => glam::Vec3::X,
        NamedKey::ArrowUp => glam::Vec3::NEG_Z,
        NamedKey::ArrowDown => glam::Vec3::Z,
        NamedKey::PageUp => glam::Vec3::Y,
        NamedKey::PageDown => glam::Vec3::NEG_Y,
        _ => return None,
    };
    Some(direction * MODEL_STEP)
}

/// How far a key turns a room's model about the vertical: Q to the left (counter-clockwise
/// seen from above), E to the right.
fn model_turn(key: &winit::keyboard::Key) -> Option<f32> {
    let winit::keyboard::Key::Character(c) = key else {
        return None;
    };
    match c.to_lowercase().as_str() {
        "q" => Some(super::ui::MODEL_TURN_DEG),
        "e" => Some(-super::ui::MODEL_TURN_DEG),
        _ => None,
    }
}

/// Metres a key press moves a room's model.
const MODEL_STEP: f32 = 0.05;
