//! Characters in parts, as artists draw them: a layered picture (PSD, OpenRaster) whose layers
//! (head, torso, each segment of each limb) overlap where they join.
//!
//! - [`layers`]: the layered picture as read ([`Layered`]), and its readers
//!   ([`read_layered`], with the feature `layers`);
//! - [`character()`]: one mesh per layer, stacked in the file's order, one texture for all, and
//!   a joint wherever two layers overlap ([`Character`]);
//! - [`joints`]: posing welds each joint's two vertices into one ([`Weld`]: dragging a hand
//!   moves the whole arm, and the joint holds exactly), and morphing places each piece so that
//!   its joints meet ([`Placement`]: exactly when the joints form a tree, in the least-squares
//!   sense, reported, when they form cycles).
//!
//! What the morph of a character guarantees: each part's shape between two keyframes is its
//! own BDMORPH frame (exact at the keyframes, each triangle's distortion bounded as for one
//! mesh); each part's rotation is its frame's; each part's translation is then chosen so that
//! its joints meet their partners. Translation changes neither shape nor distortion, so the
//! bounds hold for every part. Cost per frame: the BDMORPH frame of every part plus one pass
//! over the vertices (and, with cycles, a dense solve over the jointed pieces).
//!
//! ```
//! use bdmorph::parts::{character, CharacterOptions, Layer, Layered};
//! use bdmorph::render::Image;
//! // Two overlapping opaque rectangles on a 60 x 40 canvas: a torso and an arm.
//! let rect = |w: u32, h: u32| Image { width: w, height: h, rgba: vec![200; (w * h * 4) as usize] };
//! let layered = Layered {
//!     width: 60,
//!     height: 40,
//!     layers: vec![
//!         Layer { name: "torso".into(), image: rect(20, 30), left: 5, top: 5 },
//!         Layer { name: "arm".into(), image: rect(30, 8), left: 20, top: 10 },
//!     ],
//!     notes: vec![],
//! };
//! let c = character(&layered, &CharacterOptions::default().with_vertices(400))?;
//! assert_eq!(c.parts.len(), 2);
//! assert_eq!(c.joints.len(), 1);
//! let [a, b] = c.joints[0].vertices;
//! assert_eq!(c.mesh.positions[a as usize], c.mesh.positions[b as usize]);
//! # Ok::<(), bdmorph::parts::CharacterError>(())
//! ```

mod character;
pub mod joints;
pub mod layers;
#[cfg(feature = "layers")]
mod ora;
#[cfg(feature = "layers")]
mod psd;

pub use character::{
    atlas, character, character_with, AtlasPlaces, Character, CharacterError, CharacterOptions,
    Joint, Part, MAX_ATLAS_SIDE,
};
pub use joints::{pieces_of, JointedDeformer, Placement, PlacementReport, Weld};
pub use layers::{
    is_layered_path, layered_format, Layer, LayerBudget, Layered, LayersError, MAX_PARTS,
};
#[cfg(feature = "layers")]
pub use layers::{read_layered, read_layered_file, read_layered_with};
#[cfg(feature = "layers")]
pub use ora::{read_ora, read_ora_with};
#[cfg(feature = "layers")]
pub use psd::{read_psd, read_psd_with};
