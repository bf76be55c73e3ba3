//! The pictures the studio has read, kept within a memory budget.
//!
//! A picture costs its decoded pixels (4 bytes each) and its file's bytes (served to the page
//! as they are). The cache holds at most [`PICTURE_CACHE_BYTES`] of them; when a new one would
//! go over, the least recently used go first. A picture over the pixel budget of every picture
//! read ([`crate::render::MAX_PIXELS`]) is refused from its header before it is decoded
//! ([`crate::render::raster::decode_image`]), with its size and the limit in the message. Pictures in use (the document's picture, a
//! running export's copy) stay alive while they are used, whatever the cache dropped.

use std::collections::VecDeque;
use std::sync::Arc;

use super::open::Texture;

/// The most bytes of pictures (decoded pixels and file bytes) the studio keeps read: 320 MiB,
/// room for one 8192 x 8192 picture (256 MiB decoded) and its file, or many smaller ones.
pub const PICTURE_CACHE_BYTES: usize = 320 << 20;

/// What a picture costs in memory.
pub fn cost(texture: &Texture) -> usize {
    texture.image.rgba.len() + texture.bytes.len()
}

/// Pictures read, by name, least recently used first, within a budget of bytes.
#[derive(Debug)]
pub struct PictureCache {
    entries: VecDeque<Arc<Texture>>,
    bytes: usize,
    budget: usize,
}

impl Default for PictureCache {
    fn default() -> Self {
        Self::with_budget(PICTURE_CACHE_BYTES)
    }
}

impl PictureCache {
    /// An empty cache holding at most `budget` bytes.
    pub fn with_budget(budget: usize) -> Self {
        Self {
            entries: VecDeque::new(),
            bytes: 0,
            budget,
        }
    }

    /// The picture named `name`, if kept (it becomes the most recently used).
    pub fn get(&mut self, name: &str) -> Option<Arc<Texture>> {
        let at = self.entries.iter().position(|t| t.name == name)?;
        let t = self.entries.remove(at)?;
        self.entries.push_back(t.clone());
        Some(t)
    }

    /// Keeps `texture` (replacing one of the same name), dropping the least recently used
    /// pictures until the cache is within its budget. A picture over the whole budget is not
    /// kept (its user holds it while it is used).
    pub fn insert(&mut self, texture: Arc<Texture>) {
        self.remove(&texture.name);
        let c = cost(&texture);
        if c > self.budget {
            return;
        }
        while self.bytes + c > self.budget {
            let Some(old) = self.entries.pop_front() else {
                break;
            };
            self.bytes -= cost(&old);
        }
        self.bytes += c;
        self.entries.push_back(texture);
    }

    /// Forgets the picture named `name`.
    pub fn remove(&mut self, name: &str) {
        if let Some(at) = self.entries.iter().position(|t| t.name == name) {
            if let Some(old) = self.entries.remove(at) {
                self.bytes -= cost(&old);
            }
        }
    }

    /// The bytes kept.
    pub fn bytes(&self) -> usize {
        self.bytes
    }

    /// How many pictures are kept.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether none is kept.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::Image;

    fn picture(name: &str, side: u32) -> Arc<Texture> {
        Arc::new(Texture {
            name: name.into(),
            image: Image {
                width: side,
                height: side,
                rgba: vec![0; (side * side * 4) as usize],
            },
            bytes: vec![0; 100],
            content_type: "image/png",
        })
    }

    #[test]
    fn least_recently_used_pictures_go_first_and_the_budget_holds() {
        let one = cost(&picture("x", 10));
        let mut cache = PictureCache::with_budget(3 * one);
        cache.insert(picture("a", 10));
        cache.insert(picture("b", 10));
        cache.insert(picture("c", 10));
        assert!(cache.get("a").is_some()); // a is now the most recent
        cache.insert(picture("d", 10));
        assert!(cache.get("b").is_none(), "b was the least recently used");
        assert!(cache.get("a").is_some() && cache.get("c").is_some());
        assert_eq!(cache.len(), 3);
        assert_eq!(cache.bytes(), 3 * one);
        cache.insert(picture("huge", 40));
        assert!(
            cache.get("huge").is_none(),
            "over the whole budget: not kept"
        );
        assert!(cache.bytes() <= 3 * one);
    }
}
