//! Several lights in one frame: one shadow term per light from one camera pass.
//!
//! [`PerLight`] keeps one instance of a technique per light, made from the same name and
//! parameters, so a progressive technique's state for one light (`asm`'s tile tree, fitted
//! to that light's view) is never reused for another. Each light's result is exactly what
//! a one-light frame with that light and that instance gives.

use crate::error::{Error, Result};
use crate::light::Light;
use crate::techniques::{self, Frame, ShadowTechnique, Shadows};

/// The most lights one frame may have.
pub const MAX_LIGHTS: usize = 1024;

/// One technique, instanced per light (see the [module doc](self)).
pub struct PerLight {
    name: String,
    params: Vec<(String, String)>,
    instances: Vec<Box<dyn ShadowTechnique>>,
}

impl PerLight {
    /// The technique `name` with `params` (key, value) applied to every light's instance;
    /// fails as [`techniques::create`] and [`ShadowTechnique::set_param`] do.
    pub fn new(name: &str, params: &[(String, String)]) -> Result<Self> {
        let mut p = PerLight {
            name: name.to_string(),
            params: params.to_vec(),
            instances: Vec::new(),
        };
        p.instances.push(p.make()?);
        Ok(p)
    }

    fn make(&self) -> Result<Box<dyn ShadowTechnique>> {
        let mut t = techniques::create(&self.name)?;
        for (k, v) in &self.params {
            t.set_param(k, v)?;
        }
        Ok(t)
    }

    /// The instance that serves light `i` (made on its first frame).
    pub fn instance(&mut self, i: usize) -> Option<&mut (dyn ShadowTechnique + 'static)> {
        self.instances.get_mut(i).map(|t| t.as_mut())
    }

    /// The shadow term of `frame` for each of `lights`, in their order (`frame.light` is
    /// replaced by each in turn; everything else of the frame is shared). Light `i` is
    /// always served by the same instance, so a sequence of frames with the same lights
    /// is each light's own sequence.
    ///
    /// ```
    /// use shadowlab::prelude::*;
    /// use shadowlab::multi_light::PerLight;
    /// let scene = shadowlab::scene::load("chessboard", &Default::default()).unwrap();
    /// let mut camera = scene.camera.unwrap();
    /// (camera.width, camera.height) = (64, 48);
    /// camera.fit_depth_range(&scene.bounds);
    /// let view = ViewSamples::render(&scene, &camera);
    /// let lights = [
    ///     Light::Directional { to_light: vec3(0.3, 1.0, 0.2).normalize() },
    ///     Light::Point { position: vec3(-3.0, 6.0, 2.0) },
    /// ];
    /// let frame = Frame::new(&scene, &camera, &lights[0], &view);
    /// let shadows = PerLight::new("sm", &[]).unwrap().render(&frame, &lights).unwrap();
    /// assert_eq!(shadows.len(), 2);
    /// ```
    pub fn render(&mut self, frame: &Frame, lights: &[Light]) -> Result<Vec<Shadows>> {
        if lights.is_empty() || lights.len() > MAX_LIGHTS {
            return Err(Error::param(format!(
                "a frame needs 1..={MAX_LIGHTS} lights, not {}",
                lights.len()
            )));
        }
        for (i, l) in lights.iter().enumerate() {
            l.validate()
                .map_err(|e| Error::param(format!("light {i}: {e}")))?;
        }
        while self.instances.len() < lights.len() {
            let t = self.make()?;
            self.instances.push(t);
        }
        let mut out = Vec::with_capacity(lights.len());
        for (light, t) in lights.iter().zip(self.instances.iter_mut()) {
            let light = light.normalized();
            out.push(t.render(&Frame {
                light: &light,
                ..*frame
            })?);
        }
        Ok(out)
    }
}
