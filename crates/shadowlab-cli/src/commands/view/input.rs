//! The keys and mouse buttons the viewer answers, named once for the window's events and
//! for scripts alike, so that a script presses the same keys a person does.
//!
//! | key | does |
//! |---|---|
//! | W A S D | fly forward, left, back, right (one step a frame while held) |
//! | E Q | fly up, down |
//! | Tab, Shift+Tab | next, previous technique |
//! | `]` `[` | the technique's main parameter up, down (doubled, halved) |
//! | R | error against the reference on or off |
//! | M | the technique's images: the next one, then off |
//! | H | every overlay off or on (the view alone, as `render` draws it) |
//! | P | screenshot and the `render` command line that reproduces it |
//! | Escape | quit |
//!
//! Dragging with the left mouse button turns the camera; with the right one, the light.

use winit::event::MouseButton;
use winit::keyboard::{Key as WinitKey, NamedKey};

/// A key the viewer answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Key {
    /// Held: fly along the camera's axes.
    Move(Move),
    /// The next technique.
    NextTechnique,
    /// The previous technique.
    PreviousTechnique,
    /// The main parameter up.
    ParamUp,
    /// The main parameter down.
    ParamDown,
    /// The error overlay on or off.
    Error,
    /// The next dump image, then none.
    Dumps,
    /// Every overlay off or on.
    HideOverlays,
    /// A screenshot.
    Screenshot,
    /// Quit.
    Quit,
}

/// A direction of flight.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Move {
    /// Along the view direction.
    Forward,
    /// Against it.
    Back,
    /// To the camera's left.
    Left,
    /// To its right.
    Right,
    /// Along the camera's up.
    Up,
    /// Against it.
    Down,
}

/// Every key by its name, as scripts spell them.
pub const KEYS: &[(&str, Key)] = &[
    ("w", Key::Move(Move::Forward)),
    ("s", Key::Move(Move::Back)),
    ("a", Key::Move(Move::Left)),
    ("d", Key::Move(Move::Right)),
    ("e", Key::Move(Move::Up)),
    ("q", Key::Move(Move::Down)),
    ("tab", Key::NextTechnique),
    ("shift+tab", Key::PreviousTechnique),
    ("]", Key::ParamUp),
    ("[", Key::ParamDown),
    ("r", Key::Error),
    ("m", Key::Dumps),
    ("h", Key::HideOverlays),
    ("p", Key::Screenshot),
    ("escape", Key::Quit),
];

impl Key {
    /// The key named `name` (case-insensitive).
    pub fn from_name(name: &str) -> Option<Key> {
        let name = name.to_ascii_lowercase();
        KEYS.iter().find(|(n, _)| *n == name).map(|(_, k)| *k)
    }

    /// The key of a window's key event, `shift` telling whether Shift is down.
    pub fn from_winit(key: &WinitKey, shift: bool) -> Option<Key> {
        match key {
            WinitKey::Named(NamedKey::Tab) if shift => Some(Key::PreviousTechnique),
            WinitKey::Named(NamedKey::Tab) => Some(Key::NextTechnique),
            WinitKey::Named(NamedKey::Escape) => Some(Key::Quit),
            WinitKey::Character(c) => Key::from_name(c.as_str()),
            _ => None,
        }
    }
}

/// What a mouse drag moves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drag {
    /// The camera's view direction (left button).
    Look,
    /// The light (right button).
    Light,
}

impl Drag {
    /// The drag of a mouse button, as scripts name them: `left` or `right`.
    pub fn from_name(name: &str) -> Option<Drag> {
        match name.to_ascii_lowercase().as_str() {
            "left" => Some(Drag::Look),
            "right" => Some(Drag::Light),
            _ => None,
        }
    }

    /// The drag of a window's mouse button.
    pub fn from_winit(button: MouseButton) -> Option<Drag> {
        match button {
            MouseButton::Left => Some(Drag::Look),
            MouseButton::Right => Some(Drag::Light),
            _ => None,
        }
    }
}
