//! The viewer's camera controller: orbit around a target, pan, dolly with zoom towards the
//! cursor, an optional fly mode, and damping. Pure maths, no window: the viewer feeds it the
//! mouse and keys, and asks it for a [`Camera`] each frame.

use crate::scene::Camera;
use glam::{Vec2, Vec3};

/// Closest the orbit may come to the poles (radians from straight up or down): the view
/// direction never becomes parallel to the world's up axis, where the frame is undefined.
const POLE_MARGIN: f32 = 0.01;
/// Radians of orbit per pixel of mouse motion.
pub const ORBIT_PER_PIXEL: f32 = 0.005;
/// Distance factor per scroll step (one notch of a wheel): e^-0.1 closer.
pub const DOLLY_PER_STEP: f32 = 0.1;
/// Closest the camera may dolly to its target, as a fraction of the scene's size.
const MIN_DISTANCE_FRACTION: f32 = 1e-3;

/// Orbit state: the eye sits at `distance` from `target`, in the direction given by `yaw`
/// (about the world's up axis, +Y) and `pitch` (above the horizontal plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Orbit {
    pub target: Vec3,
    pub distance: f32,
    pub yaw: f32,
    pub pitch: f32,
}

impl Orbit {
    /// The orbit that reproduces a camera looking at a point `focus` away along its view.
    pub fn from_camera(camera: &Camera, focus: f32) -> Orbit {
        let d = -camera.forward; // from the target towards the eye
        Orbit {
            target: camera.position + camera.forward * focus,
            distance: focus,
            yaw: d.x.atan2(d.z),
            pitch: d.y.clamp(-1.0, 1.0).asin(),
        }
    }

    /// Unit vector from the target towards the eye.
    pub fn back(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(cp * sy, sp, cp * cy)
    }

    pub fn eye(&self) -> Vec3 {
        self.target + self.back() * self.distance
    }

    /// The pinhole camera of this orbit.
    pub fn camera(&self, fov_y: f32, width: u32, height: u32) -> Camera {
        let forward = -self.back();
        // The pitch stays inside the poles, so forward × Y is never zero.
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        Camera {
            position: self.eye(),
            forward,
            right,
            up,
            fov_y,
            width,
            height,
        }
    }

    fn clamp(&mut self, min_distance: f32) {
        let limit = std::f32::consts::FRAC_PI_2 - POLE_MARGIN;
        self.pitch = self.pitch.clamp(-limit, limit);
        self.yaw = self.yaw.rem_euclid(std::f32::consts::TAU);
        self.distance = self.distance.max(min_distance);
    }
}

/// The controller: an orbit, its velocities (for damping) and the scene file's view to reset to.
#[derive(Clone, Debug)]
pub struct CameraController {
    pub orbit: Orbit,
    pub fov_y: f32,
    /// The scene file's view (`reset`).
    pub home: Orbit,
    /// Seconds for a motion to decay to 1/e after the input stops; 0 = no damping.
    pub damping: f32,
    /// Fly mode: the mouse turns the view about the eye and keys move the eye.
    pub fly: bool,
    /// Fly speed, scene units per second.
    pub fly_speed: f32,
    min_distance: f32,
    /// Orbit velocity (yaw, pitch) in radians per second, pan velocity in scene units per
    /// second, dolly rate in log-distance per second.
    spin: Vec2,
    slide: Vec3,
    zoom: f32,
    /// The zoom's anchor: the point under the cursor at the target's depth.
    zoom_anchor: Option<Vec3>,
}

/// Below this speed a damped motion counts as stopped (radians or log-distance per second,
/// relative to the distance for pans).
const REST: f32 = 1e-3;

impl CameraController {
    /// A controller starting at `camera`, orbiting a target `focus` away along its view;
    /// `scene_size` (the scene's diagonal) scales the fly speed and the closest dolly.
    pub fn new(camera: &Camera, focus: f32, scene_size: f32) -> CameraController {
        let size = if scene_size.is_finite() && scene_size > 0.0 {
            scene_size
        } else {
            1.0
        };
        let focus = if focus.is_finite() && focus > 0.0 {
            focus
        } else {
            0.5 * size
        };
        let orbit = Orbit::from_camera(camera, focus);
        CameraController {
            orbit,
            fov_y: camera.fov_y,
            home: orbit,
            damping: 0.12,
            fly: false,
            fly_speed: 0.25 * size,
            min_distance: MIN_DISTANCE_FRACTION * size,
            spin: Vec2::ZERO,
            slide: Vec3::ZERO,
            zoom: 0.0,
            zoom_anchor: None,
        }
    }

    pub fn camera(&self, width: u32, height: u32) -> Camera {
        self.orbit.camera(self.fov_y, width, height)
    }

    /// Back to the scene file's view, at rest.
    pub fn reset(&mut self) {
        self.orbit = self.home;
        self.stop();
    }

    /// Stops every motion at once.
    pub fn stop(&mut self) {
        self.spin = Vec2::ZERO;
        self.slide = Vec3::ZERO;
        self.zoom = 0.0;
        self.zoom_anchor = None;
    }

    /// Whether a damped motion is still running.
    pub fn moving(&self) -> bool {
        self.spin.length() > REST
            || self.slide.length() > REST * self.orbit.distance
            || self.zoom.abs() > REST
    }

    /// Orbit by a mouse drag of `(dx, dy)` pixels (right and down positive). In fly mode the
    /// view turns about the eye instead of the target.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        let d = Vec2::new(-dx, dy) * ORBIT_PER_PIXEL;
        if self.fly {
            self.look(d);
        } else {
            self.impulse_spin(d);
        }
    }

    /// Pan by a drag of `(dx, dy)` pixels in a view `height` pixels high: the point under the
    /// cursor at the target's depth follows the cursor.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let cam = self.camera(1, 1);
        let per_pixel = 2.0 * self.orbit.distance * (0.5 * self.fov_y).tan() / height.max(1.0);
        let delta = (-dx * cam.right + dy * cam.up) * per_pixel;
        self.impulse_slide(delta);
    }

    /// Dolly by `steps` wheel notches (positive: closer) towards the point under the cursor,
    /// `cursor` in normalised device coordinates (x right, y up, -1..1; `None`: the centre) of
    /// a view with aspect `width / height`. The point under the cursor at the target's depth
    /// stays under the cursor.
    pub fn dolly(&mut self, steps: f32, cursor: Option<Vec2>, aspect: f32) {
        let anchor = cursor.map(|c| self.point_at_target_depth(c, aspect));
        if self.damping > 0.0 {
            self.zoom += steps * DOLLY_PER_STEP / self.damping;
            self.zoom_anchor = anchor;
        } else {
            self.apply_zoom(steps * DOLLY_PER_STEP, anchor);
        }
    }

    /// Fly: move the eye (and the target with it) by `dir` (x right, y up, z forward) for `dt`
    /// seconds at the fly speed.
    pub fn fly_move(&mut self, dir: Vec3, dt: f32) {
        let cam = self.camera(1, 1);
        let d = (dir.x * cam.right + dir.y * Vec3::Y + dir.z * cam.forward) * self.fly_speed * dt;
        self.orbit.target += d;
    }

    /// Advances the damped motions by `dt` seconds; true while something moves.
    pub fn update(&mut self, dt: f32) -> bool {
        if self.damping <= 0.0 || dt <= 0.0 {
            return false;
        }
        let decay = (-dt / self.damping).exp();
        // Integral of v·e^(-t/τ) over the step: v·τ·(1 - decay).
        let share = self.damping * (1.0 - decay);
        let spin = self.spin * share;
        if self.fly {
            self.look(spin);
        } else {
            self.orbit.yaw += spin.x;
            self.orbit.pitch += spin.y;
        }
        self.orbit.target += self.slide * share;
        let zoom = self.zoom * share;
        let anchor = self.zoom_anchor;
        self.apply_zoom(zoom, anchor);
        self.spin *= decay;
        self.slide *= decay;
        self.zoom *= decay;
        self.orbit.clamp(self.min_distance);
        let moving = self.moving();
        if !moving {
            self.stop();
        }
        moving
    }

    fn impulse_spin(&mut self, d: Vec2) {
        if self.damping > 0.0 {
            self.spin += d / self.damping;
        } else {
            self.orbit.yaw += d.x;
            self.orbit.pitch += d.y;
            self.orbit.clamp(self.min_distance);
        }
    }

    fn impulse_slide(&mut self, d: Vec3) {
        if self.damping > 0.0 {
            self.slide += d / self.damping;
        } else {
            self.orbit.target += d;
        }
    }

    /// Turns the view about the eye by (yaw, pitch) radians: the eye stays, the target moves.
    fn look(&mut self, d: Vec2) {
        let eye = self.orbit.eye();
        self.orbit.yaw += d.x;
        self.orbit.pitch -= d.y;
        self.orbit.clamp(self.min_distance);
        self.orbit.target = eye - self.orbit.back() * self.orbit.distance;
    }

    /// Scales the distance by e^-amount, moving the target towards `anchor` so that the
    /// anchor stays where it is on the screen.
    fn apply_zoom(&mut self, amount: f32, anchor: Option<Vec3>) {
        if amount == 0.0 {
            return;
        }
        let f = (-amount).exp();
        let d = (self.orbit.distance * f).max(self.min_distance);
        let f = d / self.orbit.distance;
        if let Some(a) = anchor {
            // Eye, target and anchor scale about the anchor's depth plane with the same factor,
            // which keeps the anchor's projection fixed.
            self.orbit.target = a + (self.orbit.target - a) * f;
        }
        self.orbit.distance = d;
    }

    /// The point on the plane through the target facing the view that projects to `ndc`.
    pub fn point_at_target_depth(&self, ndc: Vec2, aspect: f32) -> Vec3 {
        let cam = self.camera(1, 1);
        let t = (0.5 * self.fov_y).tan() * self.orbit.distance;
        self.orbit.target + cam.right * (ndc.x * t * aspect) + cam.up * (ndc.y * t)
    }
}

/// Where `p` lands on the screen of `cam`, in normalised device coordinates (x right, y up);
/// `None` behind the camera.
pub fn project(cam: &Camera, p: Vec3) -> Option<Vec2> {
    let d = p - cam.position;
    let z = d.dot(cam.forward);
    if z <= 1e-6 {
        return None;
    }
    let t = (0.5 * cam.fov_y).tan();
    let aspect = cam.width as f32 / cam.height.max(1) as f32;
    Some(Vec2::new(
        d.dot(cam.right) / (z * t * aspect),
        d.dot(cam.up) / (z * t),
    ))
}

/// Azimuth and elevation, in degrees, of the direction a directional light comes from
/// (`-direction`): azimuth about +y from +x towards +z, elevation above the xz plane.
pub fn light_angles(direction: Vec3) -> (f32, f32) {
    let to_light = -direction.normalize_or(Vec3::NEG_Y);
    let az = to_light.z.atan2(to_light.x).to_degrees();
    let el = to_light.y.clamp(-1.0, 1.0).asin().to_degrees();
    (az, el)
}

/// The light's `direction` (the way its light travels) for a light seen at `az`, `el`
/// degrees ([`light_angles`]' inverse).
pub fn light_direction(az: f32, el: f32) -> Vec3 {
    let (az, el) = (az.to_radians(), el.clamp(-90.0, 90.0).to_radians());
    -Vec3::new(el.cos() * az.cos(), el.sin(), el.cos() * az.sin())
}

/// Highest elevation a drag takes a directional light to: short of the pole, where the
/// azimuth is undefined.
pub const MAX_LIGHT_ELEVATION: f32 = 89.0;

/// A directional light dragged `dx`, `dy` pixels: right turns it about the up axis the way
/// an orbit turns the camera, up raises it, at [`ORBIT_PER_PIXEL`] radians per pixel.
pub fn drag_light_direction(direction: Vec3, dx: f32, dy: f32) -> Vec3 {
    let (az, el) = light_angles(direction);
    let per_px = ORBIT_PER_PIXEL.to_degrees();
    light_direction(
        az + dx * per_px,
        (el - dy * per_px).clamp(-MAX_LIGHT_ELEVATION, MAX_LIGHT_ELEVATION),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The dragon scene's camera at 64 × 48.
    fn scene_camera() -> Camera {
        Camera::look_at(
            Vec3::new(0.3, 1.5, 3.6),
            Vec3::new(0.0, 0.55, 0.0),
            Vec3::Y,
            40.0,
            64,
            48,
        )
        .unwrap()
    }

    fn start() -> CameraController {
        let cam = scene_camera();
        let focus = (Vec3::new(0.0, 0.55, 0.0) - cam.position).length();
        let mut c = CameraController::new(&cam, focus, 10.0);
        c.damping = 0.0;
        c
    }

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).length() <= tol
    }

    /// Float tolerance for positions a few units from the origin after a handful of
    /// trigonometric round trips: about 100 ulps of the coordinates.
    const TOL: f32 = 1e-4;

    #[test]
    fn the_orbit_reproduces_the_scene_camera() {
        let cam = scene_camera();
        let c = start();
        let back = c.camera(64, 48);
        assert!(close(back.position, cam.position, TOL), "{back:?}");
        assert!(close(back.forward, cam.forward, TOL));
        assert!(close(back.right, cam.right, TOL));
        assert!(close(back.up, cam.up, TOL));
        assert!(close(c.orbit.target, Vec3::new(0.0, 0.55, 0.0), TOL));
    }

    #[test]
    fn orbiting_keeps_the_distance_and_the_target_and_stops_at_the_poles() {
        let mut c = start();
        let (target, dist) = (c.orbit.target, c.orbit.distance);
        c.orbit(120.0, -40.0);
        assert!(close(c.orbit.target, target, TOL));
        assert!((c.orbit.eye() - target).length() - dist < TOL);
        assert_ne!(c.camera(64, 48).position, start().camera(64, 48).position);
        // Dragging far up never flips the camera over the pole.
        c.orbit(0.0, 1e6);
        let cam = c.camera(64, 48);
        assert!(cam.up.y > 0.0 && cam.forward.y < -0.99, "{cam:?}");
        assert!(cam.right.is_finite() && cam.up.is_finite());
    }

    #[test]
    fn panning_moves_eye_and_target_together_and_follows_the_cursor() {
        let mut c = start();
        let before = c.camera(64, 48);
        let p = c.orbit.target;
        c.pan(10.0, 0.0, 48.0);
        let after = c.camera(64, 48);
        assert!(close(after.forward, before.forward, TOL));
        // The old target moved 10 pixels right on the screen: 10/24 of the half-height in ndc y
        // units, times the aspect's inverse in x.
        let ndc = project(&after, p).unwrap();
        let expected = 10.0 / 24.0 / (64.0 / 48.0);
        assert!((ndc.x - expected).abs() < 1e-4, "{ndc}");
        assert!(ndc.y.abs() < 1e-4);
    }

    #[test]
    fn dolly_towards_the_cursor_keeps_the_point_under_it() {
        let mut c = start();
        let cursor = Vec2::new(0.5, -0.3);
        let aspect = 64.0 / 48.0;
        let p = c.point_at_target_depth(cursor, aspect);
        let d0 = c.orbit.distance;
        c.dolly(3.0, Some(cursor), aspect);
        assert!((c.orbit.distance - d0 * (-0.3f32).exp()).abs() < 1e-4);
        let ndc = project(&c.camera(64, 48), p).unwrap();
        assert!((ndc - cursor).length() < 1e-4, "{ndc} vs {cursor}");
        // Without a cursor the target stays.
        let t = c.orbit.target;
        c.dolly(-2.0, None, aspect);
        assert!(close(c.orbit.target, t, TOL));
        // It never passes through the target.
        c.dolly(1e4, None, aspect);
        assert!(c.orbit.distance >= 1e-3 * 10.0 * 0.999);
    }

    #[test]
    fn damping_spreads_a_drag_over_time_to_the_same_end_and_then_rests() {
        let mut undamped = start();
        undamped.orbit(100.0, 20.0);
        let mut damped = start();
        damped.damping = 0.1;
        damped.orbit(100.0, 20.0);
        // Nothing happens before time passes; then motion continues and settles.
        assert_eq!(damped.orbit.yaw, start().orbit.yaw);
        assert!(damped.update(0.016));
        let mut steps = 0;
        while damped.update(0.016) {
            steps += 1;
            assert!(steps < 10_000, "never came to rest");
        }
        assert!(!damped.moving());
        // The damped motion covers the same angle (within the rest threshold's leftover:
        // REST × τ radians).
        let dyaw = (damped.orbit.yaw - undamped.orbit.yaw).abs();
        assert!(dyaw < 1e-3, "{dyaw}");
        assert!((damped.orbit.pitch - undamped.orbit.pitch).abs() < 1e-3);
    }

    #[test]
    fn fly_mode_turns_about_the_eye_and_moves_forward() {
        let mut c = start();
        c.fly = true;
        let eye = c.orbit.eye();
        c.orbit(50.0, 10.0);
        assert!(close(c.orbit.eye(), eye, TOL));
        let f = c.camera(1, 1).forward;
        c.fly_move(Vec3::Z, 2.0);
        let moved = c.orbit.eye() - eye;
        assert!(close(moved, f * c.fly_speed * 2.0, 1e-3), "{moved}");
    }

    #[test]
    fn reset_returns_to_the_scene_view_at_rest() {
        let mut c = start();
        c.damping = 0.1;
        c.orbit(300.0, 50.0);
        c.update(0.05);
        c.pan(5.0, 5.0, 48.0);
        c.reset();
        assert_eq!(c.orbit, c.home);
        assert!(!c.moving());
        assert!(!c.update(0.016));
    }

    #[test]
    fn projection_inverts_the_camera_rays() {
        let c = start();
        let cam = c.camera(64, 48);
        let p = cam.position + cam.ray_dir(48.0, 12.0) * 2.5;
        let ndc = project(&cam, p).unwrap();
        // Pixel (48, 12) of 64 × 48: ndc (0.5, 0.5).
        assert!((ndc - Vec2::new(0.5, 0.5)).length() < 1e-4, "{ndc}");
        assert!(project(&cam, cam.position - cam.forward).is_none());
    }

    /// Light angles round-trip, name the direction the light comes from, and a drag turns
    /// and raises it without crossing the pole.
    #[test]
    fn light_direction_round_trips_and_drags() {
        // From +x, 30° up: the light travels towards -x and down.
        let d = light_direction(0.0, 30.0);
        assert!(close(d, -Vec3::new(0.866_025_4, 0.5, 0.0), TOL), "{d}");
        for (az, el) in [(0.0, 45.0), (120.0, 10.0), (-75.0, -20.0), (179.0, 80.0)] {
            let (a, e) = light_angles(light_direction(az, el));
            // Degrees after asin/atan2 of f32 components: ~1e-3° (asin loses digits near
            // the poles; 80° is the steepest case here).
            assert!(
                (a - az).abs() < 1e-3 && (e - el).abs() < 1e-3,
                "{az} {el}: {a} {e}"
            );
        }
        let start = light_direction(0.0, 30.0);
        let turned = drag_light_direction(start, 100.0, 0.0);
        let (a, e) = light_angles(turned);
        let expect = 100.0 * ORBIT_PER_PIXEL.to_degrees();
        assert!(
            (a - expect).abs() < 1e-3 && (e - 30.0).abs() < 1e-3,
            "{a} {e}"
        );
        // Dragging up (negative dy) raises the light, and stops short of the pole.
        let (_, e) = light_angles(drag_light_direction(start, 0.0, -20.0));
        assert!(e > 30.0, "{e}");
        let (_, e) = light_angles(drag_light_direction(start, 0.0, -1e5));
        assert!((e - MAX_LIGHT_ELEVATION).abs() < 1e-2, "{e}");
        assert!(turned.is_normalized());
    }
}
