//! The model's emotion space as `analyze --write-model` and `edit` set it: the emotion
//! component or components, each emotion's point, and a fitted space's axes.

use std::collections::BTreeMap;

use super::{
    check_emotion_levels, check_emotion_space, EmotionLevels, EmotionPoint, FittedSpace, IcaModel,
    ModelError, Role,
};

impl IcaModel {
    /// Marks component `k` (or none) as the emotion component. Also sets its role to
    /// [`Role::Emotion`] and resets a previous emotion component's role to [`Role::Unknown`].
    ///
    /// # Errors
    /// [`ModelError::ComponentOutOfRange`] when `k >= components`.
    pub fn set_emotion_component(&mut self, k: Option<usize>) -> Result<(), ModelError> {
        if let Some(k) = k {
            self.check_component("emotion component", k)?;
        }
        if let Some(old) = self.emotion.component {
            if self.roles[old] == Role::Emotion {
                self.roles[old] = Role::Unknown;
            }
        }
        if let Some(k) = k {
            self.roles[k] = Role::Emotion;
        }
        self.emotion.component = k;
        Ok(())
    }

    /// Names a value of the emotion component (replacing a level of the same name).
    ///
    /// # Errors
    /// [`ModelError::NonFiniteLevel`] when `value` is NaN or infinite.
    pub fn set_emotion_level(&mut self, name: &str, value: f64) -> Result<(), ModelError> {
        if !value.is_finite() {
            return Err(ModelError::NonFiniteLevel {
                name: name.to_string(),
            });
        }
        self.emotion.levels.insert(name.to_string(), value);
        Ok(())
    }

    /// Sets the emotion space: its components (ascending, at least one) and each emotion's
    /// point over them. The components get [`Role::Emotion`] (components no longer in the space
    /// go back to [`Role::Unknown`]); the main component (`main`, one of them) and its scalar
    /// levels are kept for tools that read one component.
    ///
    /// # Errors
    /// [`ModelError::ComponentOutOfRange`] for a component outside the model or a `main` not in
    /// the space, [`ModelError::NonFiniteLevel`] for a non-finite or misshapen point.
    pub fn set_emotion_space(
        &mut self,
        components: Vec<usize>,
        main: usize,
        points: BTreeMap<String, EmotionPoint>,
        persistence: Vec<f64>,
    ) -> Result<(), ModelError> {
        if !(persistence.is_empty() || persistence.len() == components.len())
            || persistence.iter().any(|v| !v.is_finite())
        {
            return Err(ModelError::NonFiniteLevel {
                name: "persistence".into(),
            });
        }
        check_emotion_space(&components, &points, self.components())?;
        let main_at =
            components
                .iter()
                .position(|&k| k == main)
                .ok_or(ModelError::ComponentOutOfRange {
                    what: "main emotion component",
                    index: main,
                    components: self.components(),
                })?;
        for (k, role) in self.roles.iter_mut().enumerate() {
            if *role == Role::Emotion && !components.contains(&k) {
                *role = Role::Unknown;
            }
        }
        for &k in &components {
            self.roles[k] = Role::Emotion;
        }
        self.emotion = EmotionLevels {
            component: Some(main),
            levels: points
                .iter()
                .map(|(name, p)| (name.clone(), p.level[main_at]))
                .collect(),
            components,
            points,
            persistence,
            ..EmotionLevels::default()
        };
        Ok(())
    }

    /// Sets a fitted emotion space ([`crate::interpret::emotion_basis`]): its axes as weights
    /// on the components, the moves along them, each emotion's point and spread over the
    /// axes, their persistence, and how it was found. `components` are the components whose
    /// levels differ between emotions (they get [`Role::Emotion`] as with
    /// [`IcaModel::set_emotion_space`]); `levels` are the main component's level per emotion,
    /// for tools that read one component.
    ///
    /// # Errors
    /// [`ModelError::ComponentOutOfRange`] for a component outside the model,
    /// [`ModelError::NonFiniteLevel`] for misshapen or non-finite axes, moves or points.
    pub fn set_fitted_space(
        &mut self,
        components: Vec<usize>,
        main: Option<usize>,
        levels: BTreeMap<String, f64>,
        space: FittedSpace,
    ) -> Result<(), ModelError> {
        let fitted = EmotionLevels {
            component: main,
            levels,
            components,
            points: space.points,
            persistence: space.persistence,
            axes: space.axes,
            moves: space.moves,
            conditioning: Some(space.conditioning),
        };
        check_emotion_levels(&fitted, self.components())?;
        for (k, role) in self.roles.iter_mut().enumerate() {
            if *role == Role::Emotion && !fitted.components.contains(&k) {
                *role = Role::Unknown;
            }
        }
        for &k in &fitted.components {
            self.roles[k] = Role::Emotion;
        }
        self.emotion = fitted;
        Ok(())
    }

    /// Forgets the emotion space (components back to [`Role::Unknown`], no points).
    pub fn clear_emotion_space(&mut self) {
        for role in &mut self.roles {
            if *role == Role::Emotion {
                *role = Role::Unknown;
            }
        }
        self.emotion = EmotionLevels::default();
    }

    /// Removes a named emotion level, returning its value.
    pub fn remove_emotion_level(&mut self, name: &str) -> Option<f64> {
        self.emotion.points.remove(name);
        self.emotion.levels.remove(name)
    }
}
