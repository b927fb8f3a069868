//! Every committed module as a `seam::Model`, for code that picks a model by name at run time.

use seam::Model;

/// Every committed module, in the order of `models/` and then the variants.
///
/// ```
/// let names: Vec<String> = generated::models().iter().map(|m| m.module.clone()).collect();
/// assert!(names.iter().any(|n| n == "cart_pendulum") && names.iter().any(|n| n == "cart_pendulum_baked"));
/// ```
pub fn models() -> Vec<Model> {
    vec![
        crate::cart_pendulum::model(),
        crate::three_body::model(),
        crate::satellite_boom::model(),
        crate::cartesian_pendulum::model(),
        crate::rolling_disk::model(),
        crate::spring_cart::model(),
        crate::pendulum_on_cart_5::model(),
        crate::stiff_pendulum::model(),
        crate::bicycle::model(),
        crate::bouncing_ball::model(),
        crate::inverted_pendulum::model(),
        crate::tumbling_body::model(),
        crate::three_body_quaternion::model(),
        crate::satellite_boom_quaternion::model(),
        crate::winch::model(),
        crate::cart_pendulum_baked::model(),
        crate::three_body_split::model(),
        crate::three_body_drop::model(),
        crate::bicycle_lagrange::model(),
    ]
}

/// The committed module called `module`.
///
/// ```
/// let model = generated::find("three_body").unwrap();
/// assert_eq!(model.coordinates.len(), 8);
/// assert!(generated::find("no_such_model").is_none());
/// ```
pub fn find(module: &str) -> Option<Model> {
    models().into_iter().find(|m| m.module == module)
}
