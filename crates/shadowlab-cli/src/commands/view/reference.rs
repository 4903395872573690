//! The error against the reference, computed in the background: a worker thread builds
//! the ray tracer's BVH once and traces the reference of the latest view it is asked
//! for (older requests are dropped unseen), then wakes the window. The viewer shows it
//! only while the view is still the one it was traced for.

use crate::config::plan::reference_spp_for;
use shadowlab::area_light::AreaLight;
use shadowlab::camera::Camera;
use shadowlab::frame::{Frame, Visibility};
use shadowlab::light::Light;
use shadowlab::reference::Reference;
use shadowlab::sampling::{pattern, PatternKind};
use shadowlab::scene::Scene;
use shadowlab::soft_reference::soft_visibility;
use shadowlab::view::ViewSamples;
use std::sync::{Condvar, Mutex, MutexGuard};
use std::thread::{Scope, ScopedJoinHandle};

/// What the reference is traced for: a view (camera, light) and its samples per pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key {
    /// The view's number: it changes whenever the camera or the light moves.
    pub view: u64,
    /// Samples per pixel.
    pub spp: u32,
}

/// The reference samples per pixel of a technique's verdict, as `compare` takes them.
pub fn spp_for(technique: &str) -> u32 {
    reference_spp_for(technique, None)
}

/// A request: the view to trace.
struct Request {
    key: Key,
    camera: Camera,
    light: Light,
    area: Option<AreaLight>,
    light_samples: u32,
    view: ViewSamples,
}

/// A traced reference.
pub struct Traced {
    /// What it was traced for.
    pub key: Key,
    /// Its shadow term.
    pub visibility: Visibility,
}

#[derive(Default)]
struct Slot {
    request: Option<Request>,
    done: Option<Traced>,
    quit: bool,
}

/// The worker's mailbox.
#[derive(Default)]
pub struct Background {
    slot: Mutex<Slot>,
    wake: Condvar,
}

impl Background {
    fn lock(&self) -> MutexGuard<'_, Slot> {
        self.slot.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Starts the worker on `scene`; `ready` is called (on the worker) after each trace.
    pub fn start<'s, 'e>(
        &'s self,
        scope: &'s Scope<'s, 'e>,
        scene: &'s Scene,
        ready: impl Fn() + Send + 's,
    ) -> ScopedJoinHandle<'s, ()> {
        scope.spawn(move || {
            let mut reference: Option<Reference> = None;
            while let Some(req) = self.next_request() {
                let r = reference.get_or_insert_with(|| Reference::build(scene));
                let frame = Frame::new(scene, &req.camera, &req.light, &req.view)
                    .with_area(req.area.as_ref(), req.light_samples);
                let samples = pattern(PatternKind::Grid, req.key.spp)
                    .expect("the techniques' reference counts are valid");
                // As `compare` traces it: under an area light the soft reference.
                let visibility = match &req.area {
                    Some(a) => {
                        soft_visibility(r, &frame, a, req.light_samples, &samples).visibility
                    }
                    None => r.visibility(&frame, &samples),
                };
                self.lock().done = Some(Traced {
                    key: req.key,
                    visibility,
                });
                ready();
            }
        })
    }

    /// Waits for the next request; `None` once asked to quit.
    fn next_request(&self) -> Option<Request> {
        let mut slot = self.lock();
        loop {
            if slot.quit {
                return None;
            }
            if let Some(r) = slot.request.take() {
                return Some(r);
            }
            slot = self.wake.wait(slot).unwrap_or_else(|e| e.into_inner());
        }
    }

    /// Asks for the reference of a view under `light` (its area light, when it has one,
    /// and the light samples a pixel under it), replacing any request not yet started.
    pub fn request(
        &self,
        key: Key,
        camera: &Camera,
        (light, area, light_samples): (&Light, Option<&AreaLight>, u32),
        view: &ViewSamples,
    ) {
        self.lock().request = Some(Request {
            key,
            camera: *camera,
            light: *light,
            area: area.copied(),
            light_samples,
            view: view.clone(),
        });
        self.wake.notify_all();
    }

    /// The latest traced reference, if one came since the last call.
    pub fn take(&self) -> Option<Traced> {
        self.lock().done.take()
    }

    /// Stops the worker after its current trace.
    pub fn quit(&self) {
        self.lock().quit = true;
        self.wake.notify_all();
    }
}
