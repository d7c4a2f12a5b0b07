//! Linking and evaluating parsed definitions (`src/common/calfunc.c`'s meaning): every name is
//! resolved once, in the scope it was written in (a file's own definitions, then `rayinit.cal`'s,
//! then the ray's channels and the library), so that evaluation walks a tree of indices.
//!
//! Evaluation has no side effects, so arguments are evaluated before the call, except for
//! `if` and `select`, which evaluate only the branch they take (recursive definitions end
//! through them). A name passed as an argument that names a function passes the function
//! (`dot(D, N)` in `rayinit.cal`). What Radiance reports as a compute error (a domain error, an
//! out-of-range `select` or `arg`, recursion deeper than [`MAX_DEPTH`]) evaluates to NaN here;
//! the pattern that called it decides what that means.

use super::parse::{Definition, Expr, Operator};
use crate::error::SourceLocation;
use crate::SceneError;
use std::collections::HashMap;

/// Calls nested deeper than this evaluate to NaN (an endless recursion).
pub const MAX_DEPTH: u32 = 512;

/// Calls with at most this many arguments pass them on the stack.
const ARGS_ON_STACK: usize = 8;

/// Definitions of at most this many nodes are written into their callers ...
const INLINE_SIZE: usize = 24;
/// ... up to this many levels deep.
const INLINE_DEPTH: u32 = 8;

/// The number of nodes of an expression.
fn size(node: &Node) -> usize {
    match node {
        Node::Negate(a) => 1 + size(a),
        Node::Binary(_, a, b) => 1 + size(a) + size(b),
        Node::Call(_, args) => 1 + args.iter().map(size).sum::<usize>(),
        _ => 1,
    }
}

/// True for arguments that cost nothing to evaluate twice.
fn is_simple(node: &Node) -> bool {
    matches!(
        node,
        Node::Number(_) | Node::Channel(_) | Node::Param(_) | Node::Variable(_)
    )
}

/// `body` with its parameters replaced by `args`; `None` where that would evaluate a costly
/// argument more than once, use a function as a value or call a value.
fn substitute(body: &Node, args: &[Node]) -> Option<Node> {
    fn uses(node: &Node, counts: &mut [usize]) {
        match node {
            Node::Param(i) | Node::FunctionArg(Callee::Param(i)) => counts[*i as usize] += 1,
            Node::Negate(a) => uses(a, counts),
            Node::Binary(_, a, b) => {
                uses(a, counts);
                uses(b, counts);
            }
            Node::Call(c, a) => {
                if let Callee::Param(i) = c {
                    counts[*i as usize] += 1;
                }
                a.iter().for_each(|a| uses(a, counts));
            }
            _ => {}
        }
    }
    fn go(node: &Node, args: &[Node]) -> Option<Node> {
        Some(match node {
            Node::Param(i) => match args.get(*i as usize)? {
                Node::FunctionArg(_) => return None,
                a => a.clone(),
            },
            Node::FunctionArg(Callee::Param(i)) => match args.get(*i as usize)? {
                f @ Node::FunctionArg(_) => f.clone(),
                _ => return None,
            },
            Node::Negate(a) => Node::Negate(Box::new(go(a, args)?)),
            Node::Binary(op, a, b) => {
                Node::Binary(*op, Box::new(go(a, args)?), Box::new(go(b, args)?))
            }
            Node::Call(c, a) => {
                let callee = match c {
                    Callee::Param(i) => match args.get(*i as usize)? {
                        Node::FunctionArg(Callee::Known(f)) => Callee::Known(*f),
                        _ => return None,
                    },
                    known => *known,
                };
                let a = a.iter().map(|a| go(a, args)).collect::<Option<Vec<_>>>()?;
                Node::Call(callee, a.into_boxed_slice())
            }
            other => other.clone(),
        })
    }
    let mut counts = vec![0usize; args.len()];
    uses(body, &mut counts);
    if counts
        .iter()
        .zip(args)
        .any(|(&n, a)| n > 1 && !is_simple(a) && !matches!(a, Node::FunctionArg(_)))
    {
        return None;
    }
    go(body, args)
}

/// The ray's values a function sees (Radiance's channels, `func.c`'s `chanvalue`), already in
/// the function's coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Channels {
    /// `Dx, Dy, Dz`: the ray's unit direction (towards the surface).
    pub direction: [f64; 3],
    /// `Nx, Ny, Nz`: the surface's unit normal.
    pub normal: [f64; 3],
    /// `Px, Py, Pz`: the point.
    pub point: [f64; 3],
    /// `T`: the distance from the ray's start.
    pub distance: f64,
    /// `Rdot`: minus the cosine between the ray and the normal (positive on the front).
    pub rdot: f64,
    /// `S`: the scale of the function's coordinates.
    pub scale: f64,
    /// `Tx, Ty, Tz`: the world origin in the function's coordinates.
    pub origin: [f64; 3],
    /// `Ix…Kz`: the world's unit vectors in the function's coordinates.
    pub axes: [[f64; 3]; 3],
    /// `Ts`: the single (shadow) ray's distance.
    pub shadow_distance: f64,
    /// `Lu, Lv`: a mesh's local coordinates.
    pub uv: [f64; 2],
}

/// The library's functions (`rayinit.cal`'s list of what is predefined).
#[allow(missing_docs)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Library {
    If,
    Select,
    Min,
    Max,
    Sqrt,
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Atan2,
    Floor,
    Ceil,
    Exp,
    Log,
    Log10,
    Erf,
    Erfc,
    Rand,
    Arg,
    /// `noise3.c`'s functions ([`super::noise`]).
    Noise3,
    Noise3x,
    Noise3y,
    Noise3z,
    Fnoise3,
}

impl Library {
    fn named(name: &str) -> Option<Library> {
        use Library::*;
        Some(match name {
            "if" => If,
            "select" => Select,
            "min" => Min,
            "max" => Max,
            "sqrt" => Sqrt,
            "sin" => Sin,
            "cos" => Cos,
            "tan" => Tan,
            "asin" => Asin,
            "acos" => Acos,
            "atan" => Atan,
            "atan2" => Atan2,
            "floor" => Floor,
            "ceil" => Ceil,
            "exp" => Exp,
            "log" => Log,
            "log10" => Log10,
            "erf" => Erf,
            "erfc" => Erfc,
            "rand" => Rand,
            "arg" => Arg,
            "noise3" => Noise3,
            "noise3x" => Noise3x,
            "noise3y" => Noise3y,
            "noise3z" => Noise3z,
            "fnoise3" => Fnoise3,
            _ => return None,
        })
    }

    /// `(fewest, most)` arguments.
    fn arity(self) -> (usize, usize) {
        use Library::*;
        match self {
            If => (3, 3),
            Select => (2, usize::MAX),
            Min | Max => (1, usize::MAX),
            Atan2 => (2, 2),
            Noise3 | Noise3x | Noise3y | Noise3z | Fnoise3 => (3, 3),
            _ => (1, 1),
        }
    }
}

/// Radiance's channel names, in `chanvalue`'s order.
const CHANNELS: [&str; 27] = [
    "Dx", "Dy", "Dz", "Nx", "Ny", "Nz", "Px", "Py", "Pz", "T", "Rdot", "S", "Tx", "Ty", "Tz", "Ix",
    "Iy", "Iz", "Jx", "Jy", "Jz", "Kx", "Ky", "Kz", "Ts", "Lu", "Lv",
];

/// Names Radiance defines for textures and prisms only, which no pattern ircache reads has.
const UNAVAILABLE: [&str; 10] = [
    "NxP", "NyP", "NzP", "RdotP", "CrP", "CgP", "CbP", "DxA", "DyA", "DzA",
];

/// A function to call: a definition or the library's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Function {
    /// Definition `i` of the program.
    Defined(u32),
    /// A library function.
    Library(Library),
}

/// Who a call calls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Callee {
    Known(Function),
    /// The function passed as parameter `i`.
    Param(u16),
}

/// A linked expression.
#[allow(missing_docs)]
#[derive(Clone, Debug, PartialEq)]
pub enum Node {
    Number(f64),
    Channel(u8),
    Param(u16),
    Variable(u32),
    Negate(Box<Node>),
    Binary(Operator, Box<Node>, Box<Node>),
    Call(Callee, Box<[Node]>),
    /// A function passed as an argument.
    FunctionArg(Callee),
}

/// An argument's value: a number or a function.
#[derive(Clone, Copy, Debug)]
enum Value {
    Number(f64),
    Function(Function),
}

#[derive(Clone)]
struct Linked {
    name: String,
    arity: Option<usize>,
    body: Node,
}

/// Linked definitions: `rayinit.cal`'s, then those of the files read, each file in its own scope.
pub struct Program {
    definitions: Vec<Linked>,
    /// The names visible to expressions written for this program (its last file's scope).
    scope: HashMap<String, u32>,
}

impl std::fmt::Debug for Program {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // Every definition, so that a scene's hash changes with its function files.
        for d in &self.definitions {
            write!(f, "{}/{:?}={:?};", d.name, d.arity, d.body)?;
        }
        Ok(())
    }
}

/// What a definition's names can see while it is linked.
struct Scope<'a> {
    names: &'a HashMap<String, u32>,
    params: &'a [String],
    arities: &'a [Option<usize>],
}

impl Program {
    /// Links `files` (each a list of definitions) after `rayinit` (the global definitions): a
    /// file sees its own definitions (the last of each name), then `rayinit`'s.
    pub fn link(rayinit: &[Definition], files: &[Vec<Definition>]) -> Result<Program, SceneError> {
        let mut all: Vec<&Definition> = rayinit.iter().collect();
        let global = scope_of(0, &all);
        let mut scopes = vec![(0..all.len(), global.clone())];
        let mut scope = global.clone();
        for file in files {
            let start = all.len();
            all.extend(file.iter());
            let mut s = global.clone();
            s.extend(scope_of(start, &all[start..]));
            scopes.push((start..all.len(), s.clone()));
            scope = s;
        }
        let arities: Vec<Option<usize>> = all
            .iter()
            .map(|d| d.params.as_ref().map(Vec::len))
            .collect();
        let mut definitions = Vec::with_capacity(all.len());
        for (range, names) in &scopes {
            for d in &all[range.clone()] {
                let params = d.params.as_deref().unwrap_or(&[]);
                let s = Scope {
                    names,
                    params,
                    arities: &arities,
                };
                definitions.push(Linked {
                    name: d.name.clone(),
                    arity: d.params.as_ref().map(Vec::len),
                    body: link(&d.body, &s, &d.location)?,
                });
            }
        }
        Ok(Program { definitions, scope })
    }

    /// Links an expression written against this program (a modifier's argument).
    pub fn compile(&self, e: &Expr, at: &SourceLocation) -> Result<Node, SceneError> {
        let arities: Vec<Option<usize>> = self.definitions.iter().map(|d| d.arity).collect();
        link(
            e,
            &Scope {
                names: &self.scope,
                params: &[],
                arities: &arities,
            },
            at,
        )
    }

    /// The function `name` of `arity` arguments, as a modifier names one (`flatcorr`).
    pub fn function(
        &self,
        name: &str,
        arity: usize,
        at: &SourceLocation,
    ) -> Result<Function, SceneError> {
        if let Some(&i) = self.scope.get(name) {
            return match self.definitions[i as usize].arity {
                Some(n) if n == arity => Ok(Function::Defined(i)),
                Some(n) => Err(SceneError::at(
                    at.clone(),
                    format!("function '{name}' takes {n} argument(s), here {arity}"),
                )),
                None => Err(SceneError::at(
                    at.clone(),
                    format!("'{name}' is a variable, where a function was expected"),
                )),
            };
        }
        match Library::named(name) {
            Some(l) if (l.arity().0..=l.arity().1).contains(&arity) => Ok(Function::Library(l)),
            _ => Err(SceneError::at(
                at.clone(),
                format!("no function '{name}' of {arity} argument(s) is defined"),
            )),
        }
    }

    /// This program for a modifier whose real arguments are `args`: every variable and
    /// subexpression that depends on neither the ray nor a function's parameters is replaced by
    /// its value (`DEGREE`, `A1`, `AC - .5`), so that evaluations per ray skip them. Values are
    /// the same as the general program's.
    #[must_use]
    pub fn specialized(&self, args: &[f64]) -> Program {
        let mut p = Program {
            definitions: self.definitions.clone(),
            scope: self.scope.clone(),
        };
        let channels = Channels::default();
        let ctx = Context {
            channels: &channels,
            args,
        };
        // Variables first, until none changes (one may depend on another).
        loop {
            let mut changed = false;
            for i in 0..p.definitions.len() {
                let d = &p.definitions[i];
                if d.arity.is_none()
                    && !matches!(d.body, Node::Number(_))
                    && p.is_constant(&d.body, false, 0)
                {
                    let v = p.value(&d.body, &[], &ctx, 0);
                    p.definitions[i].body = Node::Number(v);
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        // Each pass reads the bodies as they were before it (a recursive definition sees its
        // own), then replaces them all.
        let folded: Vec<Node> = p
            .definitions
            .iter()
            .map(|d| p.folded(d.body.clone(), &ctx))
            .collect();
        for (d, body) in p.definitions.iter_mut().zip(folded) {
            d.body = body;
        }
        // Small functions and variables written into their callers, then folded again.
        let inlined: Vec<Node> = p
            .definitions
            .iter()
            .map(|d| p.folded(p.inlined(d.body.clone(), 0), &ctx))
            .collect();
        for (d, body) in p.definitions.iter_mut().zip(inlined) {
            d.body = body;
        }
        p
    }

    /// `node` with calls of small definitions and references to small variables replaced by
    /// their bodies (parameters substituted), so that a ray's evaluation makes fewer calls.
    fn inlined(&self, node: Node, depth: u32) -> Node {
        match node {
            Node::Negate(a) => Node::Negate(Box::new(self.inlined(*a, depth))),
            Node::Binary(op, a, b) => Node::Binary(
                op,
                Box::new(self.inlined(*a, depth)),
                Box::new(self.inlined(*b, depth)),
            ),
            Node::Variable(j) => {
                let body = &self.definitions[j as usize].body;
                if depth < INLINE_DEPTH && size(body) <= INLINE_SIZE {
                    self.inlined(body.clone(), depth + 1)
                } else {
                    Node::Variable(j)
                }
            }
            Node::Call(c, args) => {
                let args: Vec<Node> = args
                    .into_vec()
                    .into_iter()
                    .map(|a| self.inlined(a, depth))
                    .collect();
                if let Callee::Known(Function::Defined(j)) = c {
                    let body = &self.definitions[j as usize].body;
                    if depth < INLINE_DEPTH && size(body) <= INLINE_SIZE {
                        if let Some(b) = substitute(body, &args) {
                            return self.inlined(b, depth + 1);
                        }
                    }
                }
                Node::Call(c, args.into_boxed_slice())
            }
            other => other,
        }
    }

    /// `node` with its constant subexpressions replaced by their values (see
    /// [`Self::specialized`]).
    #[must_use]
    pub fn fold(&self, node: Node, args: &[f64]) -> Node {
        let channels = Channels::default();
        let ctx = Context {
            channels: &channels,
            args,
        };
        let node = self.folded(node, &ctx);
        self.folded(self.inlined(node, 0), &ctx)
    }

    fn folded(&self, node: Node, ctx: &Context) -> Node {
        if !matches!(node, Node::Number(_)) && self.is_constant(&node, false, 0) {
            return Node::Number(self.value(&node, &[], ctx, 0));
        }
        match node {
            Node::Negate(a) => Node::Negate(Box::new(self.folded(*a, ctx))),
            Node::Binary(op, a, b) => Node::Binary(
                op,
                Box::new(self.folded(*a, ctx)),
                Box::new(self.folded(*b, ctx)),
            ),
            Node::Call(c, args) => Node::Call(
                c,
                args.into_vec()
                    .into_iter()
                    .map(|a| self.folded(a, ctx))
                    .collect(),
            ),
            other => other,
        }
    }

    /// True when `node` depends on no channel (nor, unless `params`, on a parameter): calls of
    /// library functions and of definitions whose bodies are alike, variables already values.
    fn is_constant(&self, node: &Node, params: bool, depth: u32) -> bool {
        if depth > 16 {
            return false;
        }
        match node {
            Node::Number(_) => true,
            Node::Param(_) => params,
            Node::Channel(_) | Node::FunctionArg(_) => false,
            Node::Variable(j) => matches!(self.definitions[*j as usize].body, Node::Number(_)),
            Node::Negate(a) => self.is_constant(a, params, depth),
            Node::Binary(_, a, b) => {
                self.is_constant(a, params, depth) && self.is_constant(b, params, depth)
            }
            Node::Call(Callee::Param(_), _) => false,
            Node::Call(Callee::Known(f), args) => {
                args.iter().all(|a| self.is_constant(a, params, depth))
                    && match f {
                        Function::Library(_) => true,
                        Function::Defined(j) => {
                            self.is_constant(&self.definitions[*j as usize].body, true, depth + 1)
                        }
                    }
            }
        }
    }

    /// True when evaluating `node` may read one of the channels `which` (by their numbers in
    /// `chanvalue`'s order), through the variables and functions it uses.
    #[must_use]
    pub fn reads_channels(&self, node: &Node, which: &[u8]) -> bool {
        let mut seen = vec![false; self.definitions.len()];
        self.reads(node, which, &mut seen)
    }

    /// [`Self::reads_channels`] for a call of `f`.
    #[must_use]
    pub fn function_reads_channels(&self, f: Function, which: &[u8]) -> bool {
        match f {
            Function::Library(_) => false,
            Function::Defined(i) => {
                let mut seen = vec![false; self.definitions.len()];
                seen[i as usize] = true;
                self.reads(&self.definitions[i as usize].body, which, &mut seen)
            }
        }
    }

    fn reads(&self, node: &Node, which: &[u8], seen: &mut [bool]) -> bool {
        let definition = |i: u32, seen: &mut [bool]| {
            let i = i as usize;
            !std::mem::replace(&mut seen[i], true)
                && self.reads(&self.definitions[i].body, which, seen)
        };
        match node {
            Node::Channel(c) => which.contains(c),
            Node::Number(_) | Node::Param(_) => false,
            Node::Variable(i) => definition(*i, seen),
            Node::Negate(a) => self.reads(a, which, seen),
            Node::Binary(_, a, b) => self.reads(a, which, seen) || self.reads(b, which, seen),
            Node::FunctionArg(c) | Node::Call(c, _)
                if matches!(c, Callee::Known(Function::Defined(_))) =>
            {
                let Callee::Known(Function::Defined(i)) = c else {
                    unreachable!()
                };
                let args_read = match node {
                    Node::Call(_, args) => args.iter().any(|a| self.reads(a, which, seen)),
                    _ => false,
                };
                args_read || definition(*i, seen)
            }
            Node::Call(_, args) => args.iter().any(|a| self.reads(a, which, seen)),
            Node::FunctionArg(_) => false,
        }
    }

    /// The value of `node` for the ray `channels` and the modifier's real arguments `args`.
    #[must_use]
    pub fn eval(&self, node: &Node, channels: &Channels, args: &[f64]) -> f64 {
        let ctx = Context { channels, args };
        self.value(node, &[], &ctx, 0)
    }

    /// `f(x…)` for the ray `channels` and the real arguments `args`.
    #[must_use]
    pub fn call(&self, f: Function, x: &[f64], channels: &Channels, args: &[f64]) -> f64 {
        let ctx = Context { channels, args };
        if x.len() <= ARGS_ON_STACK {
            let mut values = [Value::Number(0.0); ARGS_ON_STACK];
            for (v, &x) in values.iter_mut().zip(x) {
                *v = Value::Number(x);
            }
            self.apply(f, &values[..x.len()], &ctx, 0)
        } else {
            let values: Vec<Value> = x.iter().map(|&v| Value::Number(v)).collect();
            self.apply(f, &values, &ctx, 0)
        }
    }

    fn value(&self, node: &Node, frame: &[Value], ctx: &Context, depth: u32) -> f64 {
        if depth > MAX_DEPTH {
            return f64::NAN;
        }
        match node {
            Node::Number(v) => *v,
            Node::Channel(c) => ctx.channel(*c),
            Node::Param(i) => match frame.get(*i as usize) {
                Some(Value::Number(v)) => *v,
                _ => f64::NAN,
            },
            Node::Variable(i) => {
                self.value(&self.definitions[*i as usize].body, &[], ctx, depth + 1)
            }
            Node::Negate(e) => -self.value(e, frame, ctx, depth),
            Node::Binary(op, a, b) => {
                let (a, b) = (
                    self.value(a, frame, ctx, depth),
                    self.value(b, frame, ctx, depth),
                );
                match op {
                    Operator::Add => a + b,
                    Operator::Subtract => a - b,
                    Operator::Multiply => a * b,
                    Operator::Divide => a / b,
                    Operator::Power => a.powf(b),
                }
            }
            Node::FunctionArg(_) => f64::NAN,
            Node::Call(callee, args) => {
                let f = match *callee {
                    Callee::Known(f) => f,
                    Callee::Param(i) => match frame.get(i as usize) {
                        Some(Value::Function(f)) => *f,
                        _ => return f64::NAN,
                    },
                };
                // The lazy two.
                if let Function::Library(l @ (Library::If | Library::Select)) = f {
                    return self.lazy(l, args, frame, ctx, depth);
                }
                let value = |a: &Node| match a {
                    Node::FunctionArg(Callee::Known(f)) => Value::Function(*f),
                    Node::FunctionArg(Callee::Param(i)) | Node::Param(i) => frame
                        .get(*i as usize)
                        .copied()
                        .unwrap_or(Value::Number(f64::NAN)),
                    a => Value::Number(self.value(a, frame, ctx, depth)),
                };
                // Arguments on the stack (calls are per ray: no allocation for the usual few).
                if args.len() <= ARGS_ON_STACK {
                    let mut values = [Value::Number(0.0); ARGS_ON_STACK];
                    for (v, a) in values.iter_mut().zip(args.iter()) {
                        *v = value(a);
                    }
                    self.apply(f, &values[..args.len()], ctx, depth + 1)
                } else {
                    let values: Vec<Value> = args.iter().map(value).collect();
                    self.apply(f, &values, ctx, depth + 1)
                }
            }
        }
    }

    fn lazy(&self, l: Library, args: &[Node], frame: &[Value], ctx: &Context, depth: u32) -> f64 {
        let first = self.value(&args[0], frame, ctx, depth);
        if l == Library::If {
            return if first > 0.0 {
                self.value(&args[1], frame, ctx, depth)
            } else {
                self.value(&args[2], frame, ctx, depth)
            };
        }
        let n = (first + 0.5).floor();
        if n == 0.0 {
            return (args.len() - 1) as f64;
        }
        if !(1.0..args.len() as f64).contains(&n) {
            return f64::NAN;
        }
        self.value(&args[n as usize], frame, ctx, depth)
    }

    fn apply(&self, f: Function, x: &[Value], ctx: &Context, depth: u32) -> f64 {
        if depth > MAX_DEPTH {
            return f64::NAN;
        }
        let num = |i: usize| match x.get(i) {
            Some(Value::Number(v)) => *v,
            _ => f64::NAN,
        };
        match f {
            Function::Defined(i) => {
                let d = &self.definitions[i as usize];
                if d.arity != Some(x.len()) {
                    return f64::NAN;
                }
                self.value(&d.body, x, ctx, depth + 1)
            }
            Function::Library(l) => {
                use Library::*;
                let a = num(0);
                match l {
                    If => {
                        if a > 0.0 {
                            num(1)
                        } else {
                            num(2)
                        }
                    }
                    Select => {
                        let n = (a + 0.5).floor();
                        if n == 0.0 {
                            (x.len() - 1) as f64
                        } else if (1.0..x.len() as f64).contains(&n) {
                            num(n as usize)
                        } else {
                            f64::NAN
                        }
                    }
                    Min => (0..x.len()).map(num).fold(f64::INFINITY, f64::min),
                    Max => (0..x.len()).map(num).fold(f64::NEG_INFINITY, f64::max),
                    Sqrt => a.sqrt(),
                    Sin => a.sin(),
                    Cos => a.cos(),
                    Tan => a.tan(),
                    Asin => a.asin(),
                    Acos => a.acos(),
                    Atan => a.atan(),
                    Atan2 => a.atan2(num(1)),
                    Floor => a.floor(),
                    Ceil => a.ceil(),
                    Exp => a.exp(),
                    Log => a.ln(),
                    Log10 => a.log10(),
                    Erf => erf(a),
                    Erfc => 1.0 - erf(a),
                    Rand => rand(a),
                    Arg => ctx.arg(a),
                    Noise3 => super::noise::perlin(a, num(1), num(2)),
                    Noise3x => super::noise::partial(a, num(1), num(2), 0),
                    Noise3y => super::noise::partial(a, num(1), num(2), 1),
                    Noise3z => super::noise::partial(a, num(1), num(2), 2),
                    Fnoise3 => super::noise::fractal([a, num(1), num(2)]),
                }
            }
        }
    }
}

/// The ray and the modifier's real arguments while one expression is evaluated.
struct Context<'a> {
    channels: &'a Channels,
    args: &'a [f64],
}

impl Context<'_> {
    fn channel(&self, c: u8) -> f64 {
        let ch = self.channels;
        let c = c as usize;
        match c {
            0..=2 => ch.direction[c],
            3..=5 => ch.normal[c - 3],
            6..=8 => ch.point[c - 6],
            9 => ch.distance,
            10 => ch.rdot.clamp(-1.0, 1.0),
            11 => ch.scale,
            12..=14 => ch.origin[c - 12],
            15..=23 => ch.axes[(c - 15) / 3][(c - 15) % 3],
            24 => ch.shadow_distance,
            _ => ch.uv[c - 25],
        }
    }

    /// `arg(n)`: the count for 0, else the n-th real argument.
    fn arg(&self, n: f64) -> f64 {
        let n = (n + 0.5).floor();
        if n == 0.0 {
            self.args.len() as f64
        } else if n >= 1.0 && n <= self.args.len() as f64 {
            self.args[n as usize - 1]
        } else {
            f64::NAN
        }
    }
}

/// The names a list of definitions makes visible (the last of each), indices from `start`.
fn scope_of(start: usize, defs: &[&Definition]) -> HashMap<String, u32> {
    defs.iter()
        .enumerate()
        .map(|(i, d)| (d.name.clone(), (start + i) as u32))
        .collect()
}

fn link(e: &Expr, s: &Scope, at: &SourceLocation) -> Result<Node, SceneError> {
    let err = |m: String| SceneError::at(at.clone(), m);
    Ok(match e {
        Expr::Number(v) => Node::Number(*v),
        Expr::Name(n) => {
            if let Some(i) = s.params.iter().position(|p| p == n) {
                Node::Param(i as u16)
            } else if let Some(&i) = s.names.get(n) {
                if s.arities[i as usize].is_some() {
                    return Err(err(format!("'{n}' is a function and needs arguments")));
                }
                Node::Variable(i)
            } else if let Some(c) = CHANNELS.iter().position(|c| c == n) {
                Node::Channel(c as u8)
            } else if UNAVAILABLE.contains(&n.as_str()) {
                return Err(err(format!(
                    "'{n}' is defined by Radiance only for textures, mixtures and prisms, which \
                     ircache does not read"
                )));
            } else {
                return Err(err(format!("undefined variable '{n}'")));
            }
        }
        Expr::Negate(a) => Node::Negate(Box::new(link(a, s, at)?)),
        Expr::Binary(op, a, b) => {
            Node::Binary(*op, Box::new(link(a, s, at)?), Box::new(link(b, s, at)?))
        }
        Expr::Call(name, args) => {
            let callee = if let Some(i) = s.params.iter().position(|p| p == name) {
                Callee::Param(i as u16)
            } else if let Some(&i) = s.names.get(name) {
                match s.arities[i as usize] {
                    Some(n) if n == args.len() => Callee::Known(Function::Defined(i)),
                    Some(n) => {
                        return Err(err(format!(
                            "'{name}' takes {n} argument(s), called with {}",
                            args.len()
                        )))
                    }
                    None => return Err(err(format!("'{name}' is a variable, not a function"))),
                }
            } else if let Some(l) = Library::named(name) {
                let (lo, hi) = l.arity();
                if args.len() < lo || args.len() > hi {
                    return Err(err(format!(
                        "'{name}' called with {} argument(s)",
                        args.len()
                    )));
                }
                Callee::Known(Function::Library(l))
            } else {
                return Err(err(format!("undefined function '{name}'")));
            };
            let args = args
                .iter()
                .map(|a| match a {
                    // A bare name of a function passes the function.
                    Expr::Name(n) if !s.params.contains(n) => match s.names.get(n) {
                        Some(&i) if s.arities[i as usize].is_some() => {
                            Ok(Node::FunctionArg(Callee::Known(Function::Defined(i))))
                        }
                        None if CHANNELS.iter().all(|c| c != n) => match Library::named(n) {
                            Some(l) => Ok(Node::FunctionArg(Callee::Known(Function::Library(l)))),
                            None => link(a, s, at),
                        },
                        _ => link(a, s, at),
                    },
                    a => link(a, s, at),
                })
                .collect::<Result<Vec<_>, _>>()?;
            Node::Call(callee, args.into_boxed_slice())
        }
    })
}

/// The error function (Abramowitz and Stegun 7.1.26, absolute error below 1.5e-7).
fn erf(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.327_591_1 * x.abs());
    let y = 1.0
        - (((((1.061_405_429 * t - 1.453_152_027) * t) + 1.421_413_741) * t - 0.284_496_736) * t
            + 0.254_829_592)
            * t
            * (-x * x).exp();
    y.copysign(x)
}

/// A pseudo-random value in [0, 1) that depends only on `x` (Radiance's `rand`: the same
/// argument gives the same value; the sequence is ircache's own).
fn rand(x: f64) -> f64 {
    let mut h = x.to_bits() ^ 0x9e37_79b9_7f4a_7c15;
    h = (h ^ (h >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h = (h ^ (h >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^= h >> 31;
    (h >> 11) as f64 / (1u64 << 53) as f64
}
