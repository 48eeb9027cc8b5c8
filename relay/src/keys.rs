//! The Zenoh key layout of one relayed scene, under a base key such as `robots/r1/office`.
//!
//! | key | payload |
//! |---|---|
//! | `<base>/<session>/<segment>/<generation>` | one segment's archived bytes, as in shared memory |
//! | `<base>/<session>/manifest/<generation>` | the manifest payload as in shared memory: the transport's prefix ([`ygg_transport::protocol::encode_manifest_prefix`]) then the store's manifest bytes |
//! | `<base>/alive` (liveliness token) | present while an exporter serves a live writer |
//!
//! `<session>` is the writer session in 16 hex digits, `<segment>` a segment id and
//! `<generation>` a generation, both decimal. The exporter answers a query on `<base>/**`
//! with every segment of the current snapshot and its manifest, under the same keys.

/// What a data key names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Item {
    /// A segment (opaque id) of a generation.
    Segment {
        /// The segment id.
        id: u64,
        /// Its generation.
        generation: u64,
    },
    /// The manifest of a snapshot generation.
    Manifest {
        /// The snapshot generation.
        generation: u64,
    },
}

/// A parsed data key: the writer session and what the payload is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DataKey {
    /// The writer session that published the payload.
    pub session: u64,
    /// The segment or manifest.
    pub item: Item,
}

/// The keys of one scene's relay.
#[derive(Clone, Debug)]
pub struct SceneKeys {
    base: String,
}

impl SceneKeys {
    /// Keys under `base`, which must be a plain Zenoh key (no wildcard, no empty chunk).
    ///
    /// # Errors
    /// [`KeyBaseError`] saying what is wrong with `base`.
    pub fn new(base: &str) -> Result<Self, KeyBaseError> {
        let base = base.trim_end_matches('/');
        if base.is_empty() {
            return Err(KeyBaseError::Empty);
        }
        if let Some(bad) = base
            .split('/')
            .find(|c| c.is_empty() || c.contains(['*', '$', '?', '#']))
        {
            return Err(KeyBaseError::BadChunk {
                base: base.to_owned(),
                chunk: bad.to_owned(),
            });
        }
        Ok(Self {
            base: base.to_owned(),
        })
    }

    /// The base key.
    pub fn base(&self) -> &str {
        &self.base
    }

    /// `<base>/**`: what the importer subscribes to and queries.
    pub fn all(&self) -> String {
        format!("{}/**", self.base)
    }

    /// The liveliness token of the exporter.
    pub fn alive(&self) -> String {
        format!("{}/alive", self.base)
    }

    /// The key of `item` of writer session `session`.
    pub fn data(&self, key: DataKey) -> String {
        match key.item {
            Item::Segment { id, generation } => {
                format!("{}/{:016x}/{id}/{generation}", self.base, key.session)
            }
            Item::Manifest { generation } => {
                format!("{}/{:016x}/manifest/{generation}", self.base, key.session)
            }
        }
    }

    /// Parses a data key received under [`all`](Self::all).
    ///
    /// # Errors
    /// [`DataKeyParseError`] saying why `key` is not a data key of this scene.
    pub fn parse(&self, key: &str) -> Result<DataKey, DataKeyParseError> {
        let owned = || key.to_owned();
        let rest = key
            .strip_prefix(&self.base)
            .and_then(|r| r.strip_prefix('/'))
            .ok_or_else(|| DataKeyParseError::NotUnder {
                key: owned(),
                base: self.base.clone(),
            })?;
        let chunks: Vec<&str> = rest.split('/').collect();
        let [session, what, generation] = chunks[..] else {
            return Err(DataKeyParseError::Shape { key: owned() });
        };
        let bad_session = || DataKeyParseError::Session {
            key: owned(),
            session: session.to_owned(),
        };
        if session.len() != 16 {
            return Err(bad_session());
        }
        let session = u64::from_str_radix(session, 16).map_err(|_| bad_session())?;
        let generation: u64 = generation
            .parse()
            .map_err(|_| DataKeyParseError::Generation {
                key: owned(),
                generation: generation.to_owned(),
            })?;
        let item = if what == "manifest" {
            Item::Manifest { generation }
        } else {
            let id = what.parse().map_err(|_| DataKeyParseError::Item {
                key: owned(),
                what: what.to_owned(),
            })?;
            Item::Segment { id, generation }
        };
        Ok(DataKey { session, item })
    }
}

/// The keys of `--key` for the local scene `--scene`, both checked.
///
/// # Errors
/// [`SceneArgsError`] naming the option that is wrong.
pub fn scene_keys(scene: &str, key: &str) -> Result<SceneKeys, SceneArgsError> {
    ygg_transport::service::SceneServices::new(scene).map_err(|source| SceneArgsError::Scene {
        scene: scene.to_owned(),
        source,
    })?;
    SceneKeys::new(key).map_err(SceneArgsError::Key)
}

/// `--scene` or `--key` cannot name a relayed scene.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SceneArgsError {
    /// The local scene name is invalid.
    #[error("--scene {scene:?}: {source}")]
    Scene {
        /// The name given.
        scene: String,
        /// Why it cannot name services.
        source: ygg_transport::service::SceneNameError,
    },
    /// The base key is invalid.
    #[error("--key: {0}")]
    Key(#[source] KeyBaseError),
}

/// A base key that cannot carry a scene (`--key`).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum KeyBaseError {
    /// Nothing but slashes.
    #[error("the key is empty")]
    Empty,
    /// An empty chunk or one with a wildcard or special character.
    #[error(
        "the key {base:?} has the chunk {chunk:?}: use plain non-empty chunks separated by '/' (no '*', '$', '?', '#')"
    )]
    BadChunk {
        /// The base key.
        base: String,
        /// Its offending chunk.
        chunk: String,
    },
}

/// A received key that is not a data key of this scene.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DataKeyParseError {
    /// Another scene's key (or none of ours).
    #[error("{key:?} is not under {base:?}")]
    NotUnder {
        /// The key received.
        key: String,
        /// This scene's base key.
        base: String,
    },
    /// Not `<base>/<session>/<segment|manifest>/<generation>`.
    #[error("{key:?}: expected <base>/<session>/<segment|manifest>/<generation>")]
    Shape {
        /// The key received.
        key: String,
    },
    /// The session chunk is not 16 hex digits.
    #[error("{key:?}: the session {session:?} is not 16 hex digits")]
    Session {
        /// The key received.
        key: String,
        /// Its session chunk.
        session: String,
    },
    /// The generation chunk is not a number.
    #[error("{key:?}: the generation {generation:?} is not a number")]
    Generation {
        /// The key received.
        key: String,
        /// Its generation chunk.
        generation: String,
    },
    /// The item chunk is neither `manifest` nor a segment id.
    #[error("{key:?}: {what:?} is neither \"manifest\" nor a segment id")]
    Item {
        /// The key received.
        key: String,
        /// Its item chunk.
        what: String,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn data_keys_round_trip() {
        let keys = SceneKeys::new("robots/r1/office/").expect("valid base");
        for item in [
            Item::Segment {
                id: 7,
                generation: 42,
            },
            Item::Segment {
                id: u64::MAX - 1,
                generation: u64::MAX,
            },
            Item::Manifest { generation: 3 },
        ] {
            let key = DataKey {
                session: 0xdead_beef_0123_4567,
                item,
            };
            assert_eq!(keys.parse(&keys.data(key)), Ok(key));
        }
        assert_eq!(keys.all(), "robots/r1/office/**");
    }

    #[test]
    fn foreign_keys_are_refused_with_a_reason() {
        let keys = SceneKeys::new("robots/r1/office").expect("valid base");
        for (key, says) in [
            ("robots/r2/office/0000000000000001/1/1", "not under"),
            ("robots/r1/office/garbage", "expected"),
            ("robots/r1/office/0000000000000001/1/1/1", "expected"),
            ("robots/r1/office/01/1/1", "16 hex"),
            ("robots/r1/office/000000000000000g/1/1", "16 hex"),
            ("robots/r1/office/0000000000000001/x/1", "neither"),
            ("robots/r1/office/0000000000000001/1/-1", "not a number"),
        ] {
            let err = keys.parse(key).expect_err(key).to_string();
            assert!(err.contains(says), "{key}: {err}");
        }
    }

    #[test]
    fn bad_base_keys_are_refused() {
        assert!(SceneKeys::new("").is_err());
        assert!(SceneKeys::new("a//b").is_err());
        assert!(SceneKeys::new("robots/*/office").is_err());
        assert!(SceneKeys::new("robots/**").is_err());
    }
}
