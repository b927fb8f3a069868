//! A model file's definitions checked and resolved into a [`Model`]: names looked up in their
//! scope (parameters, coordinates, rates, time functions, bodies' angular velocities), the frame
//! tree with its kinematics, bodies' masses and inertias, constraints, forces, events, the
//! quasi-velocities and the initial state, each failure located in the file.

use super::*;

/// What an expression may refer to.
#[derive(Clone, Copy, PartialEq)]
enum Scope {
    /// Parameters only.
    Parameters,
    /// Parameters, coordinates, time, time functions.
    Position,
    /// Also velocities `q'`.
    Velocity,
    /// Also `omega_x(body)` etc.
    Quasi,
}

pub(super) struct Builder<'a> {
    file: &'a str,
    source: &'a str,
    def: ModelFile,
    names: HashMap<String, Expr>,
    params: HashSet<String>,
    coords: Vec<String>,
    time_fns: HashMap<String, Symbol>,
    body_omega: HashMap<String, [Expr; 3]>,
    t: Symbol,
    /// Where each value of the file is, for errors.
    spans: std::cell::OnceCell<spans::Spans>,
}

struct ScopedResolver<'b, 'a> {
    b: &'b Builder<'a>,
    scope: Scope,
}

impl Resolver for ScopedResolver<'_, '_> {
    fn name(&self, name: &str, primes: usize) -> Result<Expr, String> {
        let b = self.b;
        let is_coord = b.coords.iter().any(|c| c == name);
        if primes > 0 {
            if !is_coord {
                return Err(format!("`{name}{}`: only coordinates have time derivatives", "'".repeat(primes)));
            }
            if primes > 1 || matches!(self.scope, Scope::Parameters | Scope::Position) {
                return Err(format!(
                    "`{name}{}` is not allowed here: {}",
                    "'".repeat(primes),
                    if primes > 1 { "accelerations never appear in a model" } else { "this expression is position-level" }
                ));
            }
            return Ok(Symbol::new(&format!("{name}'")).expr());
        }
        if self.scope == Scope::Parameters && (is_coord || name == "t") {
            return Err(format!("`{name}` is not allowed here: only parameters may appear"));
        }
        if let Some(e) = b.names.get(name) {
            return Ok(*e);
        }
        let mut known: Vec<&str> = b.names.keys().map(String::as_str).collect();
        known.sort();
        let hint = match error::closest(name, known.iter().copied()) {
            Some(c) => format!("; did you mean `{c}`?"),
            None => String::new(),
        };
        Err(format!("unknown name `{name}`{hint} (known: {})", known.join(", ")))
    }

    fn call(&self, name: &str, args: &[Ast], lower: &dyn Fn(&Ast) -> Result<Expr, LowerError>) -> Result<Expr, String> {
        let b = self.b;
        if let Some(f) = b.time_fns.get(name) {
            if self.scope == Scope::Parameters {
                return Err(format!("time function `{name}` is not allowed here"));
            }
            if args.len() != 1 {
                return Err(format!("`{name}` takes 1 argument (time), found {}", args.len()));
            }
            let a = lower(&args[0]).map_err(|e| e.message)?;
            return Ok(Expr::apply_named(*f, a));
        }
        if let Some(axis) = name.strip_prefix("omega_") {
            if self.scope != Scope::Quasi {
                return Err(format!("`{name}(..)` may only appear in quasi-velocities"));
            }
            let k = match axis {
                "x" => 0,
                "y" => 1,
                "z" => 2,
                _ => return Err(format!("unknown function `{name}`: use omega_x, omega_y or omega_z")),
            };
            let body = match args {
                [Ast { kind: AstKind::Name(n, 0), .. }] => n,
                _ => return Err(format!("`{name}` takes one body name, as in `{name}(satellite)`")),
            };
            return b.body_omega.get(body).map(|w| w[k]).ok_or_else(|| {
                // Sorted: a map's order would change the message from run to run.
                let mut known: Vec<&str> = b.body_omega.keys().map(String::as_str).collect();
                known.sort_unstable();
                format!("`{body}` is not a body (bodies: {})", known.join(", "))
            });
        }
        Err(format!("unknown function `{name}` (functions: sin, cos, tan, exp, ln, sqrt, abs, omega_x/y/z(body), and the model's time functions)"))
    }
}

impl<'a> Builder<'a> {
    pub(super) fn new(file: &'a str, source: &'a str, def: ModelFile) -> Builder<'a> {
        Builder {
            file,
            source,
            def,
            names: HashMap::new(),
            params: HashSet::new(),
            coords: Vec::new(),
            time_fns: HashMap::new(),
            body_omega: HashMap::new(),
            t: Symbol::new("t"),
            spans: std::cell::OnceCell::new(),
        }
    }

    /// The spans of the file's values, scanned on the first error.
    fn spans(&self) -> &spans::Spans {
        self.spans.get_or_init(|| spans::Spans::new(self.source))
    }

    fn err(&self, kind: ErrorKind, place: &str, needle: &str, message: String, help: &str) -> ModelError {
        let span = error::place_span(self.source, self.spans(), place, needle);
        located(kind, self.file, self.source, span, place, message, help.to_string())
    }

    /// The error of an initial value (`list` "q") or rate ("qdot") of coordinate `c`, written
    /// `src`, that evaluates to `v`, not a finite number.
    fn not_finite(&self, list: &str, what: &str, c: &str, src: &str, v: f64) -> ModelError {
        self.err(
            ErrorKind::InitialState,
            &format!("initial.{list}.{c}"),
            &format!("\"{src}\""),
            format!("the initial {what} of `{c}`, `{src}`, is not a finite number ({v})"),
            "give a value with a real, finite result (sqrt of a negative number and ln of zero have none)",
        )
    }

    /// The byte span of character `col` (1-based) of the expression `src` found at `place`.
    fn expr_span(&self, src: &str, place: &str, col: usize) -> Option<std::ops::Range<usize>> {
        let quoted = format!("\"{src}\"");
        let string = self
            .spans()
            .get(place)
            .filter(|r| self.source.get(r.clone()) == Some(quoted.as_str()))
            .or_else(|| error::place_span(self.source, self.spans(), place, &quoted))?;
        let offset: usize = src.chars().take(col.saturating_sub(1)).map(char::len_utf8).sum();
        let at = string.start + 1 + offset;
        let width = src[offset.min(src.len())..].chars().next().map_or(1, char::len_utf8);
        Some(at..at + width)
    }

    /// Parses and resolves one expression string found at `place`.
    fn expr(&self, src: &str, place: &str, scope: Scope) -> Result<Expr, ModelError> {
        let ast = parse::parse(src).map_err(|e| {
            located(
                ErrorKind::ExpressionSyntax,
                self.file,
                self.source,
                self.expr_span(src, place, e.column),
                place,
                format!("in expression `{}`, column {}: {}", error::excerpt(src, e.column), e.column, e.message),
                "expressions use + - * / ^, parentheses, numbers, names, calls like sin(x), and q' for a rate".into(),
            )
        })?;
        parse::lower(&ast, &ScopedResolver { b: self, scope }).map_err(|e| {
            let kind =
                if e.message.starts_with("unknown") || e.message.contains("is not a body") { ErrorKind::UnknownName } else { ErrorKind::ExpressionSyntax };
            located(
                kind,
                self.file,
                self.source,
                self.expr_span(src, place, e.column),
                place,
                format!("in expression `{}`, column {}: {}", error::excerpt(src, e.column), e.column, e.message),
                match kind {
                    ErrorKind::UnknownName => "declare it under `parameters` (with a value), `coordinates` or `time_functions`, or fix the spelling".into(),
                    _ => "rewrite the expression as the message says".into(),
                },
            )
        })
    }

    fn vec3(&self, v: &[String], place: &str, scope: Scope) -> Result<[Expr; 3], ModelError> {
        if v.len() != 3 {
            let needle = v.first().map(|s| format!("\"{s}\"")).unwrap_or_default();
            return Err(self.err(
                ErrorKind::Dimension,
                place,
                &needle,
                format!("expected a 3-vector, found {} entries", v.len()),
                "give exactly three components, as in [\"0\", \"-l/2\", \"0\"]",
            ));
        }
        Ok([
            self.expr(&v[0], &format!("{place}[0]"), scope)?,
            self.expr(&v[1], &format!("{place}[1]"), scope)?,
            self.expr(&v[2], &format!("{place}[2]"), scope)?,
        ])
    }

    /// Each unit names a coordinate or a parameter, and is short printable text: no markup,
    /// no control character (it is shown in plots and pages).
    fn units(&self, def: &ModelFile) -> Result<(), ModelError> {
        const MAX_UNIT_CHARS: usize = 24;
        for (name, unit) in &def.units {
            let place = format!("units.{name}");
            if !def.coordinates.contains(name) && !def.parameters.contains_key(name) && !def.inputs.contains_key(name) {
                let known: Vec<&str> = def.coordinates.iter().map(String::as_str).chain(def.parameters.keys().map(String::as_str)).collect();
                return Err(self.err(
                    ErrorKind::UnknownName,
                    &place,
                    &format!("\"{name}\""),
                    format!("`{name}` has a unit but is neither a coordinate nor a parameter (known: {})", known.join(", ")),
                    "give units to the model's coordinates and parameters, by their names",
                ));
            }
            let plain = |c: char| !c.is_control() && !"<>&\"'`\\".contains(c);
            if unit.trim().is_empty() || unit.chars().count() > MAX_UNIT_CHARS || !unit.chars().all(plain) {
                return Err(self.err(
                    ErrorKind::BadValue,
                    &place,
                    &format!("\"{}\"", unit.escape_debug()),
                    format!("the unit of `{name}` is not short plain text: {:?}", unit),
                    &format!("write a unit of 1 to {MAX_UNIT_CHARS} characters, without <, >, &, quotes or control characters, such as \"m\" or \"N m\""),
                ));
            }
        }
        Ok(())
    }

    fn check_name(&self, seen: &mut HashSet<String>, name: &str, place: &str, what: &str) -> Result<(), ModelError> {
        let valid = name.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_') && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !valid {
            return Err(self.err(
                ErrorKind::BadValue,
                place,
                &format!("\"{name}\""),
                format!("`{name}` is not a valid {what} name"),
                "names start with a letter and use letters, digits and `_`",
            ));
        }
        if ["t", "pi", "world"].contains(&name) || !seen.insert(name.to_string()) {
            return Err(self.err(
                ErrorKind::Duplicate,
                place,
                &format!("\"{name}\""),
                format!("the name `{name}` is already taken (`t`, `pi` and `world` are reserved)"),
                "give every parameter, coordinate, function, frame and body its own name",
            ));
        }
        Ok(())
    }

    pub(super) fn build(mut self) -> Result<Model, ModelError> {
        let def = self.def.clone();
        let valid_name = def.name.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) && def.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
        if !valid_name {
            return Err(self.err(
                ErrorKind::BadValue,
                "name",
                "name",
                format!("the model name {:?} is not an identifier", def.name),
                "name the model with letters, digits and `_`, starting with a letter (it names the generated module)",
            ));
        }
        // Names.
        let mut seen = HashSet::new();
        let mut parameters = Vec::new();
        // The parameters, then the inputs (parameters a run sets at every call).
        let declared = def.parameters.iter().map(|(n, v)| (n, v, false)).chain(def.inputs.iter().map(|(n, v)| (n, v, true)));
        let mut inputs = Vec::new();
        for (name, value, input) in declared {
            let (section, what, fix) = if input {
                ("inputs", "input", "give every input a finite nominal value (used where no controller sets it)")
            } else {
                ("parameters", "parameter", "give every parameter a finite number")
            };
            self.check_name(&mut seen, name, &format!("{section}.{name}"), what)?;
            if !value.is_finite() || rat_from_f64(*value).is_none() {
                let message = if input { format!("input `{name}` has no finite nominal value") } else { format!("parameter `{name}` has no finite value") };
                return Err(self.err(ErrorKind::BadValue, &format!("{section}.{name}"), &format!("\"{name}\""), message, fix));
            }
            let s = Symbol::new(name);
            self.names.insert(name.clone(), s.expr());
            self.params.insert(name.clone());
            if input {
                inputs.push(parameters.len());
            }
            parameters.push((s, *value));
        }
        if def.coordinates.is_empty() {
            return Err(self.err(
                ErrorKind::Dimension,
                "coordinates",
                "coordinates",
                "the model has no coordinates".into(),
                "list the generalized coordinates, as in coordinates: [\"theta1\", \"x\"]",
            ));
        }
        let mut coordinates = Vec::new();
        for (i, name) in def.coordinates.iter().enumerate() {
            self.check_name(&mut seen, name, &format!("coordinates[{i}]"), "coordinate")?;
            let s = Symbol::new(name);
            self.names.insert(name.clone(), s.expr());
            self.coords.push(name.clone());
            coordinates.push(s);
        }
        self.units(&def)?;
        self.names.insert("t".into(), self.t.expr());
        self.names.insert("pi".into(), Symbol::new("pi").expr());
        for name in def.time_functions.keys() {
            self.check_name(&mut seen, name, &format!("time_functions.{name}"), "function")?;
            self.time_fns.insert(name.clone(), Symbol::new(name));
        }
        let mut time_functions = Vec::new();
        for (name, src) in &def.time_functions {
            let e = self.expr(src, &format!("time_functions.{name}"), Scope::Position)?;
            if e.free_symbols().iter().any(|s| coordinates.contains(s)) {
                return Err(self.err(
                    ErrorKind::BadValue,
                    &format!("time_functions.{name}"),
                    &format!("\"{src}\""),
                    format!("time function `{name}` depends on a coordinate"),
                    "a time function may use only `t` and parameters; put state-dependent forces under `forces`",
                ));
            }
            time_functions.push((self.time_fns[name], e));
        }
        self.check_time_function_cycles(&time_functions)?;
        let velocities: Vec<Symbol> = def.coordinates.iter().map(|n| Symbol::new(&format!("{n}'"))).collect();
        let accelerations: Vec<Symbol> = def.coordinates.iter().map(|n| Symbol::new(&format!("{n}''"))).collect();
        let chain = TimeChain::new(self.t, coordinates.iter().zip(&velocities).map(|(q, v)| (*q, v.expr())).collect());

        // Frames, in dependency order, with cycle and unknown-parent detection.
        let frames = self.frames(&def, &chain, &mut seen)?;
        let frame_index = |name: &str| frames.iter().position(|f| f.name == name);

        // Bodies.
        let mut bodies = Vec::new();
        // Bodies have their own namespace: a body may share its frame's name.
        let mut body_names = HashSet::new();
        for (i, b) in def.bodies.iter().enumerate() {
            let place = format!("bodies[{i}] ({})", b.name);
            self.check_name(&mut body_names, &b.name, &place, "body")?;
            let frame = frame_index(&b.frame).ok_or_else(|| {
                self.err(
                    ErrorKind::UnknownFrame,
                    &format!("{place}.frame"),
                    &format!("\"{}\"", b.frame),
                    format!("body `{}` is on frame `{}`, which is not defined", b.name, b.frame),
                    "define the frame under `frames` or use `world`",
                )
            })?;
            let mass = self.expr(&b.mass, &format!("{place}.mass"), Scope::Parameters)?;
            let env = self.param_env(&parameters);
            let mv = mass.eval(&env).unwrap_or(f64::NAN);
            if mv.is_nan() || mv <= 0.0 {
                return Err(self.err(
                    ErrorKind::NonPositiveMass,
                    &format!("{place}.mass"),
                    &format!("\"{}\"", b.mass),
                    format!("body `{}` has mass {} = {mv}, which is not positive", b.name, b.mass),
                    "give every body a positive mass; model a massless point as a frame, not a body",
                ));
            }
            let zero = || vec!["0".to_string(), "0".to_string(), "0".to_string()];
            let com = self.vec3(b.com.as_ref().unwrap_or(&zero()), &format!("{place}.com"), Scope::Position)?;
            let inertia = self.inertia(&b.inertia, &place, &env)?;
            self.body_omega.insert(b.name.clone(), frames[frame].omega);
            let mut shapes = Vec::new();
            if let Some(def) = &b.shape {
                self.shapes(def, &format!("{place}.shape"), &env, &mut shapes)?;
            }
            bodies.push(Body { name: b.name.clone(), frame, mass, com, inertia, shapes });
        }
        if bodies.is_empty() {
            return Err(self.err(ErrorKind::Dimension, "bodies", "bodies", "the model has no bodies".into(), "add at least one body"));
        }

        // Constraints.
        let mut constraints = Vec::new();
        for (i, c) in def.constraints.iter().enumerate() {
            let one = match c {
                ConstraintDef::Velocity { name, expr } => {
                    let place = format!("constraints[{i}] ({name})");
                    let e = self.expr(expr, &place, Scope::Velocity)?;
                    // Linear in the velocities: no coefficient `d expr / d q'` contains a
                    // velocity. (A vanishing second derivative is not enough: `abs(q')` has one
                    // away from q' = 0.)
                    for v in &velocities {
                        let d1 = e.diff(*v);
                        if let Some(w) = d1.free_symbols().into_iter().find(|s| velocities.contains(s)) {
                            return Err(self.err(
                                ErrorKind::NonlinearConstraint,
                                &place,
                                &format!("\"{expr}\""),
                                format!(
                                    "constraint `{name}` is not linear in the velocities: its coefficient of {} is {d1}, which contains {}",
                                    v.name(),
                                    w.name()
                                ),
                                "write velocity constraints as a(q,t)*q' + b(q,t) = 0",
                            ));
                        }
                    }
                    Constraint::Velocity { name: name.clone(), expr: e }
                }
                ConstraintDef::Position { name, expr } => {
                    let place = format!("constraints[{i}] ({name})");
                    let e = self.expr(expr, &place, Scope::Position).map_err(|mut err| {
                        if err.message.contains("position-level") {
                            err.kind = ErrorKind::NonlinearConstraint;
                            err.help = "a position constraint uses coordinates only; write rate constraints as `Velocity`".into();
                        }
                        err
                    })?;
                    Constraint::Position { name: name.clone(), expr: e }
                }
                ConstraintDef::Rolling { name, frame, radius, axle, center } => {
                    let place = format!("constraints[{i}] ({name})");
                    let f = frame_index(frame).ok_or_else(|| {
                        self.err(
                            ErrorKind::UnknownFrame,
                            &format!("{place}.frame"),
                            &format!("\"{frame}\""),
                            format!("wheel `{name}` turns with frame `{frame}`, which is not defined"),
                            "name the frame that turns with the wheel (its spin included)",
                        )
                    })?;
                    let r = self.expr(radius, &format!("{place}.radius"), Scope::Parameters)?;
                    let env = self.param_env(&parameters);
                    let rv = r.eval(&env).unwrap_or(f64::NAN);
                    if !(rv > 0.0) {
                        return Err(self.err(
                            ErrorKind::BadValue,
                            &format!("{place}.radius"),
                            &format!("\"{radius}\""),
                            format!("wheel `{name}` has radius {radius} = {rv}, which is not positive"),
                            "give the wheel a positive radius",
                        ));
                    }
                    let axis = self.vec3(axle, &format!("{place}.axle"), Scope::Parameters)?;
                    let len = axis.iter().map(|a| a.eval(&env).unwrap_or(f64::NAN).powi(2)).sum::<f64>().sqrt();
                    if !((len - 1.0).abs() < 1e-12) {
                        return Err(self.err(
                            ErrorKind::BadValue,
                            &format!("{place}.axle"),
                            &format!("\"{}\"", axle.first().cloned().unwrap_or_default()),
                            format!("wheel `{name}`'s axle has length {len}, not 1"),
                            "give the axle as a unit vector in the frame's components, such as [\"0\", \"1\", \"0\"]",
                        ));
                    }
                    let zero = || vec!["0".to_string(), "0".to_string(), "0".to_string()];
                    let c = self.vec3(center.as_ref().unwrap_or(&zero()), &format!("{place}.center"), Scope::Position)?;
                    let rolling = crate::kinematics::rolling::contact(&frames[f], &c, &axis, r, &chain);
                    constraints.push(Constraint::Velocity { name: format!("{name}_x"), expr: rolling.slip[0] });
                    constraints.push(Constraint::Velocity { name: format!("{name}_y"), expr: rolling.slip[1] });
                    if crate::kinematics::rolling::on_the_ground(rolling.height, &coordinates, &env) {
                        continue;
                    }
                    Constraint::Position { name: format!("{name}_height"), expr: rolling.height }
                }
            };
            constraints.push(one);
        }
        if constraints.len() >= coordinates.len() {
            return Err(self.err(
                ErrorKind::Dimension,
                "constraints",
                "constraints",
                format!("{} constraints on {} coordinates leave no freedom", constraints.len(), coordinates.len()),
                "remove constraints or add coordinates",
            ));
        }

        // Forces.
        let mut forces = Vec::new();
        for (i, f) in def.forces.iter().enumerate() {
            forces.push(self.force(f, i, &frames, &bodies, &coordinates)?);
        }

        // Quasi-velocities.
        let p = coordinates.len() - constraints.len();
        let quasi_full = self.quasi(&def.quasi_velocities.full, "quasi_velocities.full", p, "p = m - r", coordinates.len(), constraints.len())?;
        let declared_ignorable = match &def.ignorable {
            IgnorableDef::Auto => None,
            IgnorableDef::Declared(list) => {
                let mut idx = Vec::new();
                for (k, n) in list.iter().enumerate() {
                    let i = def.coordinates.iter().position(|c| c == n).ok_or_else(|| {
                        self.err(
                            ErrorKind::UnknownName,
                            &format!("ignorable[{k}]"),
                            &format!("\"{n}\""),
                            format!("`{n}` is declared ignorable but is not a coordinate"),
                            "declare only coordinates as ignorable",
                        )
                    })?;
                    idx.push(i);
                }
                Some(idx)
            }
        };
        let quasi_reduced: Vec<Expr> = def
            .quasi_velocities
            .reduced
            .iter()
            .enumerate()
            .map(|(k, s)| self.expr(s, &format!("quasi_velocities.reduced[{k}]"), Scope::Quasi))
            .collect::<Result<_, _>>()?;
        for (k, u) in quasi_full.iter().chain(&quasi_reduced).enumerate() {
            for v in &velocities {
                if u.diff(*v).free_symbols().iter().any(|s| velocities.contains(s)) {
                    return Err(self.err(
                        ErrorKind::NonlinearConstraint,
                        "quasi_velocities",
                        "quasi_velocities",
                        format!("quasi-velocity {k} is not linear in the velocities"),
                        "quasi-velocities are u = Y(q,t) q' + Z(q,t)",
                    ));
                }
            }
        }

        let initial = match &def.initial {
            None => None,
            Some(init) => Some(self.initial(init, &def.coordinates, &parameters)?),
        };
        if let Some((q0, qd0)) = &initial {
            self.check_initial_constraints(&constraints, &coordinates, &velocities, q0, qd0, &parameters, &time_functions)?;
        }
        if let Some(sim) = &def.simulation
            && let Err(e) = seam::output_steps(sim.t_start, sim.t_end, sim.dt_out)
        {
            let place = match e {
                seam::GridError::NotARun { .. } => "simulation",
                seam::GridError::StepLongerThanRun { .. } | seam::GridError::TooManyOutputs { .. } => "simulation.dt_out",
            };
            return Err(self.err(ErrorKind::BadValue, place, "", format!("{e}"), "the reference run is sampled every dt_out from t_start to t_end"));
        }
        let events = self.events(&def.events, &def.coordinates)?;
        let mut scenery = Vec::new();
        if let Some(shape) = &def.scenery {
            self.shapes(shape, "scenery", &self.param_env(&parameters), &mut scenery)?;
        }
        Ok(Model {
            file: self.file.to_string(),
            source: self.source.to_string(),
            name: def.name.clone(),
            description: def.description.clone(),
            parameters,
            inputs,
            coordinates,
            velocities,
            accelerations,
            t: self.t,
            time_functions,
            frames,
            bodies,
            constraints,
            forces,
            quasi_full,
            quasi_reduced,
            declared_ignorable,
            initial,
            simulation: def.simulation.clone(),
            events,
            scenery,
            def,
        })
    }

    /// The events: unique names, `when` and the resets' values in `t`, `q`, `q'` and the
    /// parameters, resets naming coordinates only.
    fn events(&self, defs: &[schema::EventDef], coordinates: &[String]) -> Result<Vec<Event>, ModelError> {
        let mut seen = HashSet::new();
        let mut events = Vec::new();
        for (k, e) in defs.iter().enumerate() {
            let place = format!("events[{k}]");
            let valid =
                e.name.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_') && e.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !valid || !seen.insert(e.name.clone()) {
                return Err(self.err(
                    if valid { ErrorKind::Duplicate } else { ErrorKind::BadValue },
                    &format!("{place}.name"),
                    &format!("\"{}\"", e.name),
                    if valid { format!("two events are called `{}`", e.name) } else { format!("`{}` is not a valid event name", e.name) },
                    "give every event its own name of letters, digits and `_`, starting with a letter",
                ));
            }
            let when = self.expr(&e.when, &format!("{place}.when"), Scope::Velocity)?;
            let direction = match e.direction {
                schema::DirectionDef::Rising => seam::Direction::Rising,
                schema::DirectionDef::Falling => seam::Direction::Falling,
                schema::DirectionDef::Either => seam::Direction::Either,
            };
            let (mut reset_q, mut reset_qdot) = (vec![None; coordinates.len()], vec![None; coordinates.len()]);
            let action = match &e.action {
                schema::ActionDef::Stop => seam::EventAction::Stop,
                schema::ActionDef::Record => seam::EventAction::Record,
                schema::ActionDef::Reset { q, qdot } => {
                    for (map, target, what) in [(q, &mut reset_q, "q"), (qdot, &mut reset_qdot, "qdot")] {
                        for (name, src) in map {
                            let at = format!("{place}.action.{what}.{name}");
                            let i = coordinates.iter().position(|c| c == name).ok_or_else(|| {
                                self.err(
                                    ErrorKind::UnknownName,
                                    &at,
                                    &format!("\"{name}\""),
                                    format!("the reset sets `{name}`, which is not a coordinate"),
                                    &format!("name coordinates only (coordinates: {})", coordinates.join(", ")),
                                )
                            })?;
                            target[i] = Some(self.expr(src, &at, Scope::Velocity)?);
                        }
                    }
                    if q.is_empty() && qdot.is_empty() {
                        return Err(self.err(
                            ErrorKind::BadValue,
                            &format!("{place}.action"),
                            "Reset",
                            format!("event `{}` resets nothing", e.name),
                            "give the new values, as in Reset(qdot: {\"y\": \"-e*y'\"}), or use Record",
                        ));
                    }
                    seam::EventAction::Reset
                }
            };
            events.push(Event { name: e.name.clone(), direction, action, when, reset_q, reset_qdot });
        }
        Ok(events)
    }

    /// A time function that calls itself, directly or through others, has no value.
    fn check_time_function_cycles(&self, functions: &[(Symbol, Expr)]) -> Result<(), ModelError> {
        let calls = |e: Expr| -> Vec<Symbol> {
            e.post_order_nodes().iter().filter_map(|n| if let crate::symbolic::Node::Apply(f, _) = &*n.node() { Some(*f) } else { None }).collect()
        };
        let graph: HashMap<Symbol, Vec<Symbol>> = functions.iter().map(|(f, e)| (*f, calls(*e))).collect();
        for (start, _) in functions {
            // Depth-first from `start`: reaching it again is a cycle.
            let mut stack: Vec<(Symbol, Vec<Symbol>)> = vec![(*start, vec![*start])];
            let mut seen = HashSet::new();
            while let Some((f, path)) = stack.pop() {
                for g in graph.get(&f).into_iter().flatten() {
                    if g == start {
                        let names: Vec<String> = path.iter().chain([g]).map(|s| s.name()).collect();
                        let name = start.name();
                        return Err(self.err(
                            ErrorKind::Cycle,
                            &format!("time_functions.{name}"),
                            &format!("\"{name}\""),
                            format!("time function `{name}` calls itself: {}", names.join(" -> ")),
                            "define every time function in terms of `t`, parameters and functions that do not call it back",
                        ));
                    }
                    if seen.insert(*g) {
                        let mut p = path.clone();
                        p.push(*g);
                        stack.push((*g, p));
                    }
                }
            }
        }
        Ok(())
    }

    /// The model's own initial state must satisfy its constraints (the reference run starts
    /// there): each residual within `1e-9` of its magnitude.
    #[allow(clippy::too_many_arguments)]
    fn check_initial_constraints(
        &self,
        constraints: &[Constraint],
        coordinates: &[Symbol],
        velocities: &[Symbol],
        q0: &[f64],
        qd0: &[f64],
        parameters: &[(Symbol, f64)],
        time_functions: &[(Symbol, Expr)],
    ) -> Result<(), ModelError> {
        let mut env = self.param_env(parameters);
        for (f, body) in time_functions {
            env.define(*f, self.t, *body);
        }
        env.set(self.t, self.def.simulation.as_ref().map_or(0.0, |s| s.t_start));
        for (s, v) in coordinates.iter().zip(q0).chain(velocities.iter().zip(qd0)) {
            env.set(*s, *v);
        }
        // Position constraints on the coordinates, then every constraint on the rates (a
        // position constraint's time derivative, `dh/dq q' + dh/dt`).
        let rate_of = |h: Expr| coordinates.iter().zip(velocities).fold(h.diff(self.t), |acc, (q, v)| acc + h.diff(*q) * v.expr());
        let positions = constraints.iter().filter_map(|c| match c {
            Constraint::Position { name, expr } => Some((name, *expr, true)),
            Constraint::Velocity { .. } => None,
        });
        let rates = constraints.iter().map(|c| match c {
            Constraint::Velocity { name, expr } => (name, *expr, false),
            Constraint::Position { name, expr } => (name, rate_of(*expr), false),
        });
        for (name, e, position) in positions.chain(rates) {
            let residual = e.eval(&env).unwrap_or(f64::NAN);
            let bound = crate::symbolic::eval::magnitude(e).eval(&env).unwrap_or(f64::NAN);
            if !(residual.abs() <= 1e-9 * bound.max(1e-300)) {
                let kind = if constraints.iter().any(|c| matches!(c, Constraint::Position { name: n, .. } if n == name)) { "position" } else { "velocity" };
                let (place, message, help) = if position {
                    (
                        "initial.q",
                        format!("the initial coordinates violate the position constraint `{name}`: its residual is {residual:e}"),
                        "give coordinates on the constraint (solve it for one of them: a value may be an expression in the others)",
                    )
                } else {
                    (
                        "initial.qdot",
                        format!(
                            "the initial rates violate the {kind} constraint `{name}`{}: its residual is {residual:e}",
                            if kind == "position" { " (its time derivative)" } else { "" }
                        ),
                        "give rates that satisfy it: a rate may be written in terms of the others (`\"theta2\": \"-cos(theta1 - theta2)*theta1'\"`, as in scene 1)",
                    )
                };
                return Err(self.err(ErrorKind::InitialState, place, place.rsplit('.').next().unwrap_or(place), message, help));
            }
        }
        Ok(())
    }

    fn param_env(&self, parameters: &[(Symbol, f64)]) -> Env {
        let mut env = Env::default();
        for (s, v) in parameters {
            env.set(*s, *v);
        }
        env.set(Symbol::new("pi"), std::f64::consts::PI);
        env
    }

    fn frames(&self, def: &ModelFile, chain: &TimeChain, seen: &mut HashSet<String>) -> Result<Vec<FrameKinematics>, ModelError> {
        for (i, f) in def.frames.iter().enumerate() {
            self.check_name(seen, &f.name, &format!("frames[{i}]"), "frame")?;
        }
        let mut done: Vec<FrameKinematics> = vec![FrameKinematics::world()];
        let mut pending: Vec<usize> = (0..def.frames.len()).collect();
        while !pending.is_empty() {
            let before = pending.len();
            let mut still = Vec::new();
            for i in pending {
                let f = &def.frames[i];
                let Some(parent_index) = done.iter().position(|d| d.name == f.parent) else {
                    if !def.frames.iter().any(|g| g.name == f.parent) {
                        return Err(self.err(
                            ErrorKind::UnknownFrame,
                            &format!("frames[{i}] ({}).parent", f.name),
                            &format!("\"{}\"", f.parent),
                            format!("frame `{}` has parent `{}`, which is not defined", f.name, f.parent),
                            "use `world` or the name of another frame",
                        ));
                    }
                    still.push(i);
                    continue;
                };
                let parent = done[parent_index].clone();
                let place = format!("frames[{i}] ({})", f.name);
                let zero = vec!["0".to_string(), "0".to_string(), "0".to_string()];
                let translation = self.vec3(f.translation.as_ref().unwrap_or(&zero), &format!("{place}.translation"), Scope::Position)?;
                if let Some(RotationDef::Quaternion(e0, e1, e2, e3)) = f.rotation.iter().find(|r| matches!(r, RotationDef::Quaternion(..))) {
                    let rp = format!("{place}.rotation");
                    if f.rotation.len() > 1 {
                        return Err(self.err(
                            ErrorKind::BadValue,
                            &rp,
                            "Quaternion",
                            format!("frame `{}` turns by a quaternion and by other rotations", f.name),
                            "a quaternion is a frame's only rotation: put the others on a parent frame",
                        ));
                    }
                    let e = [e0, e1, e2, e3].map(|x| self.expr(x, &format!("{rp}[0]"), Scope::Position));
                    let [e0, e1, e2, e3] = e;
                    let e = [e0?, e1?, e2?, e3?];
                    done.push(parent.child_quaternion(parent_index, &f.name, &translation, &e, chain));
                    continue;
                }
                let mut turns = Vec::new();
                for (k, r) in f.rotation.iter().enumerate() {
                    let rp = format!("{place}.rotation[{k}]");
                    match r {
                        RotationDef::Quaternion(..) => unreachable!("handled above"),
                        RotationDef::X(a) => turns.push(Turn::About(Axis::X, self.expr(a, &rp, Scope::Position)?)),
                        RotationDef::Y(a) => turns.push(Turn::About(Axis::Y, self.expr(a, &rp, Scope::Position)?)),
                        RotationDef::Z(a) => turns.push(Turn::About(Axis::Z, self.expr(a, &rp, Scope::Position)?)),
                        RotationDef::EulerZYX(psi, theta, phi) => {
                            turns.push(Turn::About(Axis::Z, self.expr(psi, &rp, Scope::Position)?));
                            turns.push(Turn::About(Axis::Y, self.expr(theta, &rp, Scope::Position)?));
                            turns.push(Turn::About(Axis::X, self.expr(phi, &rp, Scope::Position)?));
                        }
                        RotationDef::Axis(axis, angle) => {
                            let a = self.vec3(axis, &format!("{rp}.axis"), Scope::Parameters)?;
                            self.check_numeric(&a, &rp, "axis", |v| {
                                let norm = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
                                ((norm - 1.0).abs() <= 1e-9).then_some(()).ok_or(format!("the axis has length {norm}, not 1"))
                            })?;
                            turns.push(Turn::Along(a, self.expr(angle, &rp, Scope::Position)?));
                        }
                        RotationDef::Matrix(rows) => {
                            if rows.len() != 3 {
                                return Err(self.err(
                                    ErrorKind::Dimension,
                                    &rp,
                                    "Matrix",
                                    format!("a rotation matrix has 3 rows, not {}", rows.len()),
                                    "write [[r11, r12, r13], [r21, r22, r23], [r31, r32, r33]]",
                                ));
                            }
                            let mut m = Vec::new();
                            for (i, row) in rows.iter().enumerate() {
                                m.push(self.vec3(row, &format!("{rp}[{i}]"), Scope::Parameters)?.to_vec());
                            }
                            let entries: Vec<Expr> = m.iter().flatten().copied().collect();
                            self.check_numeric(&entries, &rp, "Matrix", |v| {
                                let r = |i: usize, j: usize| v[3 * i + j];
                                let worst = (0..3)
                                    .flat_map(|i| (0..3).map(move |j| (i, j)))
                                    .map(|(i, j)| ((0..3).map(|k| r(k, i) * r(k, j)).sum::<f64>() - if i == j { 1.0 } else { 0.0 }).abs())
                                    .fold(0.0f64, f64::max);
                                let det = r(0, 0) * (r(1, 1) * r(2, 2) - r(1, 2) * r(2, 1)) - r(0, 1) * (r(1, 0) * r(2, 2) - r(1, 2) * r(2, 0))
                                    + r(0, 2) * (r(1, 0) * r(2, 1) - r(1, 1) * r(2, 0));
                                (worst <= 1e-9 && det > 0.0)
                                    .then_some(())
                                    .ok_or(format!("it is not a rotation (R^T R - I is off by {worst:e}, determinant {det})"))
                            })?;
                            turns.push(Turn::Fixed(Matrix::from_rows(m)));
                        }
                    }
                }
                done.push(parent.child_turned(parent_index, &f.name, &translation, &turns, chain));
            }
            if still.len() == before {
                let names: Vec<&str> = still.iter().map(|i| def.frames[*i].name.as_str()).collect();
                return Err(self.err(
                    ErrorKind::FrameCycle,
                    "frames",
                    &format!("\"{}\"", names[0]),
                    format!("the frames {} form a cycle (each is an ancestor of itself)", names.join(", ")),
                    "every chain of parents must end at `world`",
                ));
            }
            pending = still;
        }
        Ok(done)
    }

    /// The solids of `def` (at `place`), sizes positive, each one pushed onto `out`.
    fn shapes(&self, def: &ShapeDef, place: &str, env: &Env, out: &mut Vec<shape::Shape>) -> Result<(), ModelError> {
        use shape::Solid;
        // An expression in the parameters at `{place}.{at}` whose value `fits`, else refused.
        let checked = |src: &String, at: &str, fits: fn(f64) -> bool, wanted: &str, help: &str| -> Result<Expr, ModelError> {
            let e = self.expr(src, &format!("{place}.{at}"), Scope::Parameters)?;
            let value = e.eval(env).unwrap_or(f64::NAN);
            if !fits(value) {
                return Err(self.err(
                    ErrorKind::BadValue,
                    &format!("{place}.{at}"),
                    &format!("\"{src}\""),
                    format!("the shape's {at} is {src} = {value}, which is not {wanted}"),
                    help,
                ));
            }
            Ok(e)
        };
        let size = |src: &String, at: &str| checked(src, at, |v| v > 0.0 && v.is_finite(), "a positive number", "give every size of a shape a positive value");
        // Three values of `field` (a box's sides, a mesh's scale), each read by `each`.
        let three =
            |values: &Vec<String>, field: &str, count: &str, each: &dyn Fn(&String, &str) -> Result<Expr, ModelError>| -> Result<[Expr; 3], ModelError> {
                if values.len() != 3 {
                    return Err(self.err(
                        ErrorKind::Dimension,
                        &format!("{place}.{field}"),
                        &values.first().map(|s| format!("\"{s}\"")).unwrap_or_default(),
                        format!("{count}; {} were given", values.len()),
                        &format!("write {field}: [\"x\", \"y\", \"z\"]"),
                    ));
                }
                Ok([each(&values[0], &format!("{field}[0]"))?, each(&values[1], &format!("{field}[1]"))?, each(&values[2], &format!("{field}[2]"))?])
            };
        let zero = || vec!["0".to_string(), "0".to_string(), "0".to_string()];
        let placed = |origin: &Option<Vec<String>>, rpy: &Option<Vec<String>>| -> Result<([Expr; 3], [Expr; 3]), ModelError> {
            let o = self.vec3(origin.as_ref().unwrap_or(&zero()), &format!("{place}.origin"), Scope::Parameters)?;
            let r = self.vec3(rpy.as_ref().unwrap_or(&zero()), &format!("{place}.rpy"), Scope::Parameters)?;
            Ok((o, r))
        };
        let (solid, (origin, rpy)) = match def {
            ShapeDef::Compound(parts) => {
                for (k, part) in parts.iter().enumerate() {
                    self.shapes(part, &format!("{place}[{k}]"), env, out)?;
                }
                return Ok(());
            }
            ShapeDef::Box { size: sides, origin, rpy } => (Solid::Box { size: three(sides, "size", "a box has three sides", &size)? }, placed(origin, rpy)?),
            ShapeDef::Cylinder { radius, length, origin, rpy } => {
                (Solid::Cylinder { radius: size(radius, "radius")?, length: size(length, "length")? }, placed(origin, rpy)?)
            }
            ShapeDef::Capsule { radius, length, origin, rpy } => {
                (Solid::Capsule { radius: size(radius, "radius")?, length: size(length, "length")? }, placed(origin, rpy)?)
            }
            ShapeDef::Sphere { radius, origin } => (Solid::Sphere { radius: size(radius, "radius")? }, placed(origin, &None)?),
            ShapeDef::Mesh { file, scale, origin, rpy } => {
                // A factor may be negative: a mirrored part (URDF's `scale="1 -1 1"`).
                let factor = |src: &String, at: &str| {
                    checked(src, at, |v| v != 0.0 && v.is_finite(), "a number other than zero", "give each factor of a mesh's scale a value other than zero")
                };
                let scale = match scale {
                    None => [Expr::int(1), Expr::int(1), Expr::int(1)],
                    Some(v) => three(v, "scale", "a mesh's scale has three factors", &factor)?,
                };
                (Solid::Mesh { mesh: self.mesh(file, &format!("{place}.file")).map_err(Box::new), scale }, placed(origin, rpy)?)
            }
        };
        out.push(shape::Shape { solid, origin, rpy });
        Ok(())
    }

    /// The mesh of the file `file` (at `place`; STL, COLLADA or OBJ), relative to the model file's folder,
    /// simplified for drawing.
    fn mesh(&self, file: &str, place: &str) -> Result<std::sync::Arc<mesh::TriangleMesh>, ModelError> {
        let path = std::path::Path::new(self.file).parent().unwrap_or(std::path::Path::new("")).join(file);
        let refuse = |why: String, help: &str| {
            self.err(ErrorKind::Io, place, &format!("\"{file}\""), format!("the mesh `{}` {why}", files::printable_path(&path)), help)
        };
        mesh::drawn_mesh(&path).map_err(|e| match e {
            mesh::MeshError::Read(files::FileError::TooLarge { limit, .. }) => refuse(
                format!("holds more than {limit} bytes"),
                &format!("give a smaller mesh: it is drawn with at most {} triangles", mesh::MAX_DRAWN_TRIANGLES),
            ),
            mesh::MeshError::Read(e) => {
                refuse(format!("cannot be read: {}", e.source_message()), "give the path of a mesh file, relative to the model file's folder")
            }
            mesh::MeshError::Format(why) => {
                refuse(format!("cannot be drawn: {why}"), &format!("give a mesh file ({}) with at least one triangle", mesh::MESH_EXTENSIONS))
            }
        })
    }

    fn inertia(&self, def: &InertiaDef, place: &str, env: &Env) -> Result<Option<Matrix>, ModelError> {
        let p = format!("{place}.inertia");
        let m = match def {
            InertiaDef::PointMass => return Ok(None),
            InertiaDef::Diagonal(d) => {
                let v = self.vec3(d, &p, Scope::Parameters)?;
                let z = Expr::zero();
                Matrix::from_rows(vec![vec![v[0], z, z], vec![z, v[1], z], vec![z, z, v[2]]])
            }
            InertiaDef::Products { ixx, iyy, izz, ixy, ixz, iyz } => {
                let e = |s: &String, n: &str| self.expr(s, &format!("{p}.{n}"), Scope::Parameters);
                let (xx, yy, zz) = (e(ixx, "ixx")?, e(iyy, "iyy")?, e(izz, "izz")?);
                let (xy, xz, yz) = (e(ixy, "ixy")?, e(ixz, "ixz")?, e(iyz, "iyz")?);
                Matrix::from_rows(vec![vec![xx, -xy, -xz], vec![-xy, yy, -yz], vec![-xz, -yz, zz]])
            }
            InertiaDef::Matrix(rows) => {
                if rows.len() != 3 || rows.iter().any(|r| r.len() != 3) {
                    return Err(self.err(
                        ErrorKind::Dimension,
                        &p,
                        "Matrix",
                        format!("an inertia matrix is 3x3, found {} rows of lengths {:?}", rows.len(), rows.iter().map(Vec::len).collect::<Vec<_>>()),
                        "give three rows of three entries",
                    ));
                }
                let mut out = Vec::new();
                for (i, r) in rows.iter().enumerate() {
                    out.push(self.vec3(r, &format!("{p}[{i}]"), Scope::Parameters)?.to_vec());
                }
                Matrix::from_rows(out)
            }
        };
        let vals: Vec<f64> = m.data.iter().map(|e| e.eval(env).unwrap_or(f64::NAN)).collect();
        if let Some(k) = vals.iter().position(|v| !v.is_finite()) {
            return Err(self.err(
                ErrorKind::BadValue,
                &p,
                "inertia",
                format!("entry [{}][{}] of the inertia of {place} is {} with the model's parameter values: it overflows f64", k / 3, k % 3, vals[k]),
                "scale the model (other units) so that its numbers and their products stay within about 1e-150 to 1e150",
            ));
        }
        let sym = (0..3).all(|i| (0..3).all(|j| (vals[i * 3 + j] - vals[j * 3 + i]).abs() <= 1e-12 * (1.0 + vals[i * 3 + j].abs())));
        let min_eig = min_eigenvalue_sym3(&vals);
        let scale = vals.iter().map(|v| v.abs()).fold(0.0, f64::max);
        if !sym || vals.iter().any(|v| !v.is_finite()) || min_eig < -1e-12 * scale.max(1e-300) {
            return Err(self.err(
                ErrorKind::InertiaNotPsd,
                &p,
                "inertia",
                format!("the inertia of {place} is not symmetric positive semi-definite (smallest eigenvalue {min_eig:.3e}, symmetric: {sym})"),
                "check the values and the sign convention: Products(...) takes the paper's Eq. (75) form, [[Ixx, -Ixy, -Ixz], ...]",
            ));
        }
        // The principal moments of a rigid body satisfy the triangle inequality: each at most
        // the sum of the other two (`I_a + I_b = sum m (a^2 + b^2 + 2 c^2) >= I_c`).
        let trace = vals[0] + vals[4] + vals[8];
        let max_eig = trace - min_eig - middle_eigenvalue_sym3(&vals, min_eig);
        if max_eig > trace - max_eig + 1e-9 * scale.max(1e-300) {
            let others = trace - max_eig;
            return Err(self.err(
                ErrorKind::InertiaNotPsd,
                &p,
                "inertia",
                format!(
                    "the inertia of {place} is no rigid body's: its largest principal moment ({max_eig:.6e}) exceeds the sum of the other two ({others:.6e}), which no distribution of mass allows (the triangle inequality)"
                ),
                "check the values (about the centre of mass, in the body's frame): for a box of sides a, b, c, I_x = m (b^2 + c^2) / 12",
            ));
        }
        Ok(Some(m))
    }

    fn force(&self, f: &ForceDef, i: usize, frames: &[FrameKinematics], bodies: &[Body], coords: &[Symbol]) -> Result<Force, ModelError> {
        let frame = |name: &str, place: &str| {
            frames.iter().position(|f| f.name == name).ok_or_else(|| {
                self.err(
                    ErrorKind::UnknownFrame,
                    place,
                    &format!("\"{name}\""),
                    format!("frame `{name}` is not defined"),
                    "use `world` or a frame defined under `frames`",
                )
            })
        };
        // A point fixed in a frame, the end `end` of a spring or damper.
        let attach = |fr: &str, pt: &[String], end: &str, place: &str| -> Result<(usize, [Expr; 3]), ModelError> {
            Ok((frame(fr, &format!("{place}.frame_{end}"))?, self.vec3(pt, &format!("{place}.point_{end}"), Scope::Position)?))
        };
        Ok(match f {
            ForceDef::Gravity { vector } => Force::Gravity { vector: self.vec3(vector, &format!("forces[{i}] (gravity).vector"), Scope::Parameters)? },
            ForceDef::PointForce { name, frame: fr, point, force, expressed_in } => {
                let place = format!("forces[{i}] ({name})");
                let fi = frame(fr, &format!("{place}.frame"))?;
                let pt = self.vec3(point, &format!("{place}.point"), Scope::Position)?;
                let fv = self.vec3(force, &format!("{place}.force"), Scope::Velocity)?;
                let ei = frame(expressed_in.as_deref().unwrap_or("world"), &format!("{place}.expressed_in"))?;
                Force::PointForce { name: name.clone(), frame: fi, point: pt, force_world: frames[ei].to_world(&fv) }
            }
            ForceDef::Torque { name, body, torque } => {
                let place = format!("forces[{i}] ({name})");
                let bi = bodies.iter().position(|b| &b.name == body).ok_or_else(|| {
                    self.err(
                        ErrorKind::UnknownFrame,
                        &format!("{place}.body"),
                        &format!("\"{body}\""),
                        format!("body `{body}` is not defined"),
                        "name a body defined under `bodies`",
                    )
                })?;
                Force::Torque { name: name.clone(), body: bi, torque: self.vec3(torque, &format!("{place}.torque"), Scope::Velocity)? }
            }
            ForceDef::Spring { name, frame_a, point_a, frame_b, point_b, stiffness, rest_length } => {
                let place = format!("forces[{i}] ({name})");
                let (a, b) = (attach(frame_a, point_a, "a", &place)?, attach(frame_b, point_b, "b", &place)?);
                Force::Spring {
                    name: name.clone(),
                    a,
                    b,
                    stiffness: self.expr(stiffness, &format!("{place}.stiffness"), Scope::Parameters)?,
                    rest_length: self.expr(rest_length, &format!("{place}.rest_length"), Scope::Parameters)?,
                }
            }
            ForceDef::Damper { name, frame_a, point_a, frame_b, point_b, damping } => {
                let place = format!("forces[{i}] ({name})");
                let (a, b) = (attach(frame_a, point_a, "a", &place)?, attach(frame_b, point_b, "b", &place)?);
                Force::Damper { name: name.clone(), a, b, damping: self.expr(damping, &format!("{place}.damping"), Scope::Parameters)? }
            }
            ForceDef::Generalized { name, components } => {
                let place = format!("forces[{i}] ({name})");
                let mut v = vec![Expr::zero(); coords.len()];
                for (c, src) in components {
                    let k = self.coords.iter().position(|x| x == c).ok_or_else(|| {
                        self.err(
                            ErrorKind::UnknownName,
                            &format!("{place}.components"),
                            &format!("\"{c}\""),
                            format!("`{c}` is not a coordinate"),
                            "key generalized forces by coordinate name",
                        )
                    })?;
                    v[k] += self.expr(src, &format!("{place}.components.{c}"), Scope::Velocity)?;
                }
                Force::Generalized { name: name.clone(), components: v }
            }
            ForceDef::Potential { name, expr } => {
                Force::Potential { name: name.clone(), expr: self.expr(expr, &format!("forces[{i}] ({name})"), Scope::Position)? }
            }
        })
    }

    fn quasi(&self, list: &[String], place: &str, want: usize, rule: &str, m: usize, r: usize) -> Result<Vec<Expr>, ModelError> {
        if list.len() != want {
            // One quasi-velocity too few where a quaternion lacks its unit norm: the missing
            // constraint is the fault, not the list.
            if let Some((i, frame, e)) = self.quaternion_without_unit_norm()
                && list.len() + 1 == want
            {
                return Err(self.err(
                    ErrorKind::QuasiVelocityCount,
                    &format!("frames[{i}] ({frame}).rotation"),
                    &format!("\"{}\"", e[0]),
                    format!(
                        "the quaternion ({}) of frame `{frame}` has no unit-norm constraint, so the model counts {want} degrees of freedom where it has {}",
                        e.join(", "),
                        want - 1
                    ),
                    &format!(
                        "add the constraint `Position(name: \"unit\", expr: \"{}^2 + {}^2 + {}^2 + {}^2 - 1\")` under `constraints`",
                        e[0], e[1], e[2], e[3]
                    ),
                ));
            }
            let needle = place.rsplit('.').next().unwrap_or(place);
            return Err(self.err(
                ErrorKind::QuasiVelocityCount,
                place,
                needle,
                format!("{} quasi-velocities given, but {rule} = {m} - {r} = {want} are needed", list.len()),
                &format!("list exactly {want} independent combinations of the velocities"),
            ));
        }
        list.iter().enumerate().map(|(k, s)| self.expr(s, &format!("{place}[{k}]"), Scope::Quasi)).collect()
    }

    /// Checks constant entries (parameters allowed) with the file's parameter values: `test`
    /// gets their numbers and says what is wrong; located at `place`.
    fn check_numeric(&self, entries: &[Expr], place: &str, needle: &str, test: impl Fn(&[f64]) -> Result<(), String>) -> Result<(), ModelError> {
        let env = self.param_env(&self.def.parameters.iter().map(|(k, v)| (Symbol::new(k), *v)).collect::<Vec<_>>());
        let values: Vec<f64> = entries.iter().map(|e| e.eval(&env).unwrap_or(f64::NAN)).collect();
        test(&values).map_err(|why| {
            self.err(ErrorKind::BadValue, place, needle, why, "give constant numbers of a unit axis, or of a rotation matrix (orthonormal, determinant 1)")
        })
    }

    /// The first frame turned by a quaternion whose four coordinates no position constraint
    /// names together (its unit norm is missing): the frame's index, name and the quaternion.
    fn quaternion_without_unit_norm(&self) -> Option<(usize, String, [String; 4])> {
        let named = |e: &[String; 4]| {
            self.def.constraints.iter().any(|c| match c {
                ConstraintDef::Position { expr, .. } => e.iter().all(|q| expr.contains(q.as_str())),
                _ => false,
            })
        };
        self.def.frames.iter().enumerate().find_map(|(i, f)| {
            f.rotation.iter().find_map(|r| match r {
                RotationDef::Quaternion(a, b, c, d) => {
                    let e = [a.clone(), b.clone(), c.clone(), d.clone()];
                    (!named(&e)).then(|| (i, f.name.clone(), e))
                }
                _ => None,
            })
        })
    }

    fn initial(&self, init: &InitialDef, coords: &[String], parameters: &[(Symbol, f64)]) -> Result<(Vec<f64>, Vec<f64>), ModelError> {
        let mut env = self.param_env(parameters);
        let mut q = Vec::new();
        for c in coords {
            let src = init.q.get(c).ok_or_else(|| {
                self.err(
                    ErrorKind::InitialState,
                    "initial.q",
                    "initial",
                    format!("no initial value for coordinate `{c}`"),
                    "give every coordinate an initial value under initial.q",
                )
            })?;
            let v = self.expr(src, &format!("initial.q.{c}"), Scope::Parameters)?.eval(&env).unwrap_or(f64::NAN);
            if !v.is_finite() {
                return Err(self.not_finite("q", "value", c, src, v));
            }
            env.set(Symbol::new(c), v);
            q.push(v);
        }
        for k in init.q.keys().chain(init.qdot.keys()) {
            if !coords.contains(k) {
                return Err(self.err(
                    ErrorKind::UnknownName,
                    "initial",
                    &format!("\"{k}\""),
                    format!("`{k}` is not a coordinate"),
                    "key initial values by coordinate name",
                ));
            }
        }
        // Velocities may refer to one another (theta2' = -cos(..)*theta1'): evaluate in order.
        let mut qd = vec![f64::NAN; coords.len()];
        for _ in 0..coords.len() {
            for (i, c) in coords.iter().enumerate() {
                if !qd[i].is_nan() {
                    continue;
                }
                let src = init.qdot.get(c).ok_or_else(|| {
                    self.err(
                        ErrorKind::InitialState,
                        "initial.qdot",
                        "qdot",
                        format!("no initial velocity for coordinate `{c}`"),
                        "give every coordinate an initial rate under initial.qdot",
                    )
                })?;
                let e = self.expr(src, &format!("initial.qdot.{c}"), Scope::Velocity)?;
                if let Ok(v) = e.eval(&env) {
                    if !v.is_finite() {
                        return Err(self.not_finite("qdot", "rate", c, src, v));
                    }
                    qd[i] = v;
                    env.set(Symbol::new(&format!("{c}'")), v);
                }
            }
        }
        if let Some(i) = qd.iter().position(|v| v.is_nan()) {
            return Err(self.err(
                ErrorKind::InitialState,
                &format!("initial.qdot.{}", coords[i]),
                "qdot",
                format!("the initial velocity of `{}` cannot be evaluated (circular or undefined)", coords[i]),
                "write each initial rate in terms of parameters, coordinates and rates given before it",
            ));
        }
        Ok((q, qd))
    }
}

/// The middle eigenvalue of a symmetric 3 x 3 matrix (row-major) whose smallest is `min`: the
/// smaller root of the quadratic left once `min` is divided out.
fn middle_eigenvalue_sym3(a: &[f64], min: f64) -> f64 {
    let trace = a[0] + a[4] + a[8];
    // The sum of the principal 2 x 2 minors is the sum of the eigenvalues' pairwise products.
    let minors = a[0] * a[4] - a[1] * a[3] + a[0] * a[8] - a[2] * a[6] + a[4] * a[8] - a[5] * a[7];
    // The other two have sum s and product p: p = minors - min s.
    let s = trace - min;
    let p = minors - min * s;
    let disc = (s * s - 4.0 * p).max(0.0).sqrt();
    0.5 * (s - disc)
}

/// The smallest eigenvalue of a symmetric 3 x 3 matrix (row-major), by the trigonometric method.
fn min_eigenvalue_sym3(a: &[f64]) -> f64 {
    let (a11, a12, a13, a22, a23, a33) = (a[0], a[1], a[2], a[4], a[5], a[8]);
    let p1 = a12 * a12 + a13 * a13 + a23 * a23;
    if p1 == 0.0 {
        return a11.min(a22).min(a33);
    }
    let q = (a11 + a22 + a33) / 3.0;
    let p2 = (a11 - q).powi(2) + (a22 - q).powi(2) + (a33 - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let b = |x: f64| x / p;
    let (b11, b22, b33, b12, b13, b23) = (b(a11 - q), b(a22 - q), b(a33 - q), b(a12), b(a13), b(a23));
    let det = b11 * (b22 * b33 - b23 * b23) - b12 * (b12 * b33 - b23 * b13) + b13 * (b12 * b23 - b22 * b13);
    let r = (det / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    q + 2.0 * p * (phi + 2.0 * std::f64::consts::PI / 3.0).cos()
}
