//! pest parse tree → AST: one converter per grammar rule, every node spanned.
//!
//! Operator chains arrive as flat lists (see `grammar/lag.pest`) and are
//! folded here without recursion; each fold step checks the tree depth
//! against [`MAX_EXPR_DEPTH`], so no AST deeper than the limit is ever built.

use super::ast::*;
use super::depth::{
    check_paren_depth, too_deep_expr, too_long_chain, MAX_EXPR_DEPTH, MAX_TREE_HEIGHT,
};
use super::grammar::{is_statement_keyword, LagParser, Rule};
use super::syntax_error;
use crate::diagnostic::{codes, Diagnostic};
use crate::span::Span;
use pest::iterators::{Pair, Pairs};
use pest::Parser;

type Converted<T> = Result<T, Diagnostic>;

/// Parses a whole `.lag` file. Every syntax error, number too large or
/// nesting too deep comes back as a [`Diagnostic`], sorted by position.
pub fn parse(source: &str) -> Result<Model, Vec<Diagnostic>> {
    check_paren_depth(source).map_err(|d| vec![d])?;
    let mut pairs = LagParser::parse(Rule::model, source)
        .map_err(|error| vec![syntax_error::from_pest(&error, source)])?;
    match pairs.next() {
        Some(pair) => model(pair),
        None => Ok(Model::default()),
    }
}

fn model(pair: Pair<Rule>) -> Result<Model, Vec<Diagnostic>> {
    let mut items = Vec::new();
    let mut errors = Vec::new();
    for statement_pair in pair.into_inner() {
        if statement_pair.as_rule() == Rule::EOI {
            continue;
        }
        match statement(statement_pair) {
            Ok(item) => items.push(item),
            Err(error) => errors.push(error),
        }
    }
    if errors.is_empty() {
        Ok(Model { items })
    } else {
        crate::diagnostic::sort(&mut errors);
        Err(errors)
    }
}

fn statement(pair: Pair<Rule>) -> Converted<Item> {
    let span = Span::from(pair.as_span());
    let rule = pair.as_rule();
    let mut children = Children::of(pair);
    let kind = match rule {
        Rule::param => ItemKind::Param {
            name: ident(children.expect(Rule::ident)?),
            value: expr(children.expect(Rule::expr)?)?,
        },
        Rule::input => ItemKind::Input {
            name: ident(children.expect(Rule::ident)?),
            default: expr(children.expect(Rule::expr)?)?,
        },
        Rule::coords => {
            let mut names = Vec::new();
            for name in children.by_ref() {
                names.push(ident(name));
            }
            ItemKind::Coords(names)
        }
        Rule::mass => ItemKind::Mass {
            name: ident(children.expect(Rule::ident)?),
            law: expr(children.expect(Rule::expr)?)?,
        },
        Rule::lagrangian => ItemKind::Lagrangian(expr(children.expect(Rule::expr)?)?),
        Rule::constraint => {
            let lhs = expr(children.expect(Rule::expr)?)?;
            let rhs = expr(children.expect(Rule::expr)?)?;
            let candidates = match children.next() {
                Some(list) => Children::of(list).map(|v| var(v).expr).collect(),
                None => Vec::new(),
            };
            ItemKind::Constraint {
                lhs,
                rhs,
                candidates,
            }
        }
        Rule::point => point(children)?,
        Rule::force => ItemKind::Force {
            coord: ident(children.expect(Rule::ident)?),
            value: expr(children.expect(Rule::expr)?)?,
        },
        Rule::initial => {
            let mut values = Vec::new();
            for value in children.by_ref() {
                values.push(initial_value(value)?);
            }
            ItemKind::Initial(values)
        }
        Rule::time => ItemKind::Time {
            start: expr(children.expect(Rule::expr)?)?,
            end: expr(children.expect(Rule::expr)?)?,
        },
        Rule::exact => ItemKind::Exact {
            target: expr(children.expect(Rule::expr)?)?,
            value: expr(children.expect(Rule::expr)?)?,
        },
        Rule::integrator => ItemKind::Integrator(ident(children.expect(Rule::ident)?)),
        Rule::let_def => ItemKind::Let {
            name: ident(children.expect(Rule::ident)?),
            value: expr(children.expect(Rule::expr)?)?,
        },
        Rule::output => ItemKind::Output {
            name: ident(children.expect(Rule::ident)?),
            value: expr(children.expect(Rule::expr)?)?,
        },
        Rule::stop => ItemKind::Stop(expr(children.expect(Rule::expr)?)?),
        Rule::impact => {
            let cond_pair = children.expect(Rule::expr)?;
            let text = cond_pair
                .as_str()
                .split_whitespace()
                .collect::<Vec<_>>()
                .join(" ");
            let cond = expr(cond_pair)?;
            let mut resets = Vec::new();
            for pair in children.by_ref() {
                resets.push(reset(pair)?);
            }
            ItemKind::When { cond, text, resets }
        }
        _ => return Err(unexpected_tree(span)),
    };
    Ok(Item { kind, span })
}

fn point(mut children: Children) -> Converted<ItemKind> {
    let name = ident(children.expect(Rule::ident)?);
    let mut fields = Vec::new();
    for field in children {
        fields.push(point_field(field)?);
    }
    Ok(ItemKind::Point { name, fields })
}

fn point_field(pair: Pair<Rule>) -> Converted<PointField> {
    let span = Span::from(pair.as_span());
    let rule = pair.as_rule();
    let mut children = Children::of(pair);
    let kind = match rule {
        Rule::point_mass => PointFieldKind::Mass(expr(children.expect(Rule::expr)?)?),
        Rule::point_position => PointFieldKind::Position(expr(children.expect(Rule::expr)?)?),
        Rule::absolute_velocity => {
            PointFieldKind::AbsoluteVelocity(expr(children.expect(Rule::expr)?)?)
        }
        Rule::relative_velocity => {
            PointFieldKind::RelativeVelocity(expr(children.expect(Rule::expr)?)?)
        }
        _ => return Err(unexpected_tree(span)),
    };
    Ok(PointField { kind, span })
}

fn reset(pair: Pair<Rule>) -> Converted<Reset> {
    let span = Span::from(pair.as_span());
    let mut children = Children::of(pair);
    Ok(Reset {
        target: expr(children.expect(Rule::expr)?)?,
        value: expr(children.expect(Rule::expr)?)?,
        span,
    })
}

fn initial_value(pair: Pair<Rule>) -> Converted<InitialValue> {
    let span = Span::from(pair.as_span());
    let mut children = Children::of(pair);
    Ok(InitialValue {
        target: expr(children.expect(Rule::expr)?)?,
        value: expr(children.expect(Rule::expr)?)?,
        span,
    })
}

fn ident(pair: Pair<Rule>) -> Ident {
    Ident {
        name: pair.as_str().to_string(),
        span: pair.as_span().into(),
    }
}

/// An expression with its nesting depth (a chain `a + b + …` of one
/// operator is one level, however long) and the height of its tree (what
/// recursive passes descend), for the two limits.
struct Node {
    expr: Expr,
    depth: usize,
    height: usize,
}

impl Node {
    fn leaf(kind: ExprKind, span: Span) -> Node {
        Node {
            expr: Expr { kind, span },
            depth: 1,
            height: 1,
        }
    }
}

fn expr(pair: Pair<Rule>) -> Converted<Expr> {
    expression(pair).map(|node| node.expr)
}

/// `conditional | disjunction`.
fn expression(pair: Pair<Rule>) -> Converted<Node> {
    let span = Span::from(pair.as_span());
    let inner = Children::of(pair)
        .next()
        .ok_or_else(|| unexpected_tree(span))?;
    match inner.as_rule() {
        Rule::conditional => conditional(inner),
        Rule::disjunction => disjunction(inner),
        _ => Err(unexpected_tree(span)),
    }
}

/// `if cond then a else b`.
fn conditional(pair: Pair<Rule>) -> Converted<Node> {
    let span = Span::from(pair.as_span());
    let keyword = Span::new(span.start, span.start + 2);
    let mut children = Children::of(pair);
    let cond = expression(children.expect(Rule::expr)?)?;
    let then = expression(children.expect(Rule::expr)?)?;
    let otherwise = expression(children.expect(Rule::expr)?)?;
    let level = (
        cond.depth.max(then.depth).max(otherwise.depth),
        cond.height.max(then.height).max(otherwise.height),
    );
    let kind = ExprKind::If {
        cond: Box::new(cond.expr),
        then: Box::new(then.expr),
        otherwise: Box::new(otherwise.expr),
    };
    deeper(kind, span, level, keyword)
}

/// `conjunction (or conjunction)*`, folded to the left.
fn disjunction(pair: Pair<Rule>) -> Converted<Node> {
    logic_chain(pair, Rule::conjunction, LogicOp::Or, conjunction)
}

/// `negation (and negation)*`, folded to the left.
fn conjunction(pair: Pair<Rule>) -> Converted<Node> {
    logic_chain(pair, Rule::negation, LogicOp::And, negation)
}

fn logic_chain(
    pair: Pair<Rule>,
    rule: Rule,
    op: LogicOp,
    operand: fn(Pair<Rule>) -> Converted<Node>,
) -> Converted<Node> {
    let mut children = Children::of(pair);
    let mut acc = operand(children.expect(rule)?)?;
    // The keywords (`and`, `or`) are punctuation to `Children`: what
    // follows the first operand is the next operand.
    for next in children {
        if next.as_rule() != rule {
            return Err(unexpected_tree(next.as_span().into()));
        }
        let op_span = Span::from(next.as_span());
        let rhs = operand(next)?;
        let span = acc.expr.span.to(rhs.expr.span);
        let (depth, height) = (acc.depth.max(rhs.depth + 1), acc.height.max(rhs.height));
        let kind = ExprKind::Logic {
            op,
            lhs: Box::new(acc.expr),
            rhs: Box::new(rhs.expr),
        };
        acc = node_at(kind, span, depth, height + 1, op_span)?;
    }
    Ok(acc)
}

/// `not* comparison`.
fn negation(pair: Pair<Rule>) -> Converted<Node> {
    let mut nots = Vec::new();
    for child in Children::of(pair) {
        if child.as_rule() == Rule::kw_not {
            nots.push(Span::from(child.as_span()));
        } else {
            let mut node = comparison(child)?;
            for not_span in nots.into_iter().rev() {
                let span = not_span.to(node.expr.span);
                let level = (node.depth, node.height);
                node = deeper(ExprKind::Not(Box::new(node.expr)), span, level, not_span)?;
            }
            return Ok(node);
        }
    }
    Err(unexpected_tree(nots.last().copied().unwrap_or_default()))
}

/// `sum (cmp_op sum)?`.
fn comparison(pair: Pair<Rule>) -> Converted<Node> {
    let mut children = Children::of(pair);
    let lhs = sum(children.expect(Rule::sum)?)?;
    let Some(op) = children.next() else {
        return Ok(lhs);
    };
    let op_span = Span::from(op.as_span());
    let op = match op.as_str() {
        "<" => CmpOp::Less,
        "<=" => CmpOp::LessEq,
        ">" => CmpOp::Greater,
        _ => CmpOp::GreaterEq,
    };
    let rhs = sum(children.expect(Rule::sum)?)?;
    let span = lhs.expr.span.to(rhs.expr.span);
    let level = (lhs.depth.max(rhs.depth), lhs.height.max(rhs.height));
    let kind = ExprKind::Compare {
        op,
        lhs: Box::new(lhs.expr),
        rhs: Box::new(rhs.expr),
    };
    deeper(kind, span, level, op_span)
}

/// `product (add_op product)*`, folded to the left.
fn sum(pair: Pair<Rule>) -> Converted<Node> {
    let mut children = Children::of(pair);
    let mut acc = product(children.expect(Rule::product)?)?;
    while let Some(op) = children.next() {
        let op_span = Span::from(op.as_span());
        let op = if op.as_str() == "+" {
            BinOp::Add
        } else {
            BinOp::Sub
        };
        let rhs = product(children.expect(Rule::product)?)?;
        acc = chain(op, op_span, acc, rhs)?;
    }
    Ok(acc)
}

/// `unary (mul_op unary)*`, folded to the left.
fn product(pair: Pair<Rule>) -> Converted<Node> {
    let mut children = Children::of(pair);
    let mut acc = unary(children.expect(Rule::unary)?)?;
    while let Some(op) = children.next() {
        let op_span = Span::from(op.as_span());
        let op = if op.as_str() == "*" {
            BinOp::Mul
        } else {
            BinOp::Div
        };
        let rhs = unary(children.expect(Rule::unary)?)?;
        acc = chain(op, op_span, acc, rhs)?;
    }
    Ok(acc)
}

/// `neg* power`: the minus signs wrap the whole power, `-x^2` = `-(x^2)`.
fn unary(pair: Pair<Rule>) -> Converted<Node> {
    let mut negs = Vec::new();
    for child in Children::of(pair) {
        if child.as_rule() == Rule::neg {
            negs.push(Span::from(child.as_span()));
        } else {
            return negate(negs, power(child)?);
        }
    }
    Err(unexpected_tree(negs.last().copied().unwrap_or_default()))
}

/// `primary (pow_op neg* primary)*`, folded to the right: `a^b^c` =
/// `a^(b^c)` and `a^-b^c` = `a^(-(b^c))`.
fn power(pair: Pair<Rule>) -> Converted<Node> {
    let span = Span::from(pair.as_span());
    // bases[0] ^ (negs[0] bases[1] ^ (negs[1] bases[2] ^ …))
    let mut bases = Vec::new();
    let mut operators: Vec<(Span, Vec<Span>)> = Vec::new();
    for child in Children::of(pair) {
        match child.as_rule() {
            Rule::pow_op => operators.push((child.as_span().into(), Vec::new())),
            Rule::neg => match operators.last_mut() {
                Some((_, negs)) => negs.push(child.as_span().into()),
                None => return Err(unexpected_tree(span)),
            },
            _ => bases.push(postfix(child)?),
        }
    }
    let Some(mut acc) = bases.pop() else {
        return Err(unexpected_tree(span));
    };
    while let (Some(base), Some((op_span, negs))) = (bases.pop(), operators.pop()) {
        let exponent = negate(negs, acc)?;
        acc = binary(BinOp::Pow, op_span, base, exponent)?;
    }
    Ok(acc)
}

/// `primary (. axis)*`.
fn postfix(pair: Pair<Rule>) -> Converted<Node> {
    let span = Span::from(pair.as_span());
    let mut children = Children::of(pair);
    let mut acc = primary(children.next().ok_or_else(|| unexpected_tree(span))?)?;
    for component in children {
        let at = Span::from(component.as_span());
        let axis = ident(Children::of(component).expect(Rule::ident)?);
        let span = acc.expr.span.to(at);
        let kind = ExprKind::Component {
            base: Box::new(acc.expr),
            axis,
        };
        let level = (acc.depth, acc.height);
        acc = deeper(kind, span, level, at)?;
    }
    Ok(acc)
}

fn primary(pair: Pair<Rule>) -> Converted<Node> {
    let span = Span::from(pair.as_span());
    match pair.as_rule() {
        Rule::number => number(pair),
        Rule::var => Ok(var(pair)),
        Rule::call => call(pair),
        Rule::paren => {
            let mut elements = Vec::new();
            for element in Children::of(pair) {
                elements.push(expression(element)?);
            }
            if elements.len() == 1 {
                let mut node = elements.pop().ok_or_else(|| unexpected_tree(span))?;
                node.expr.span = span;
                return Ok(node);
            }
            if elements.len() > 3 {
                return Err(Diagnostic::error(
                    codes::DIMENSION_MISMATCH,
                    format!("a vector of {} components", elements.len()),
                )
                .with_primary(span, "vectors have 2 or 3 components"));
            }
            let level = level_of(&elements);
            let kind = ExprKind::Vector(elements.into_iter().map(|e| e.expr).collect());
            deeper(kind, span, level, span)
        }
        _ => Err(unexpected_tree(span)),
    }
}

fn number(pair: Pair<Rule>) -> Converted<Node> {
    let span = Span::from(pair.as_span());
    match pair.as_str().parse::<f64>() {
        Ok(value) if value.is_finite() => Ok(Node::leaf(ExprKind::Number(value), span)),
        _ => Err(
            Diagnostic::error(codes::NUMBER_TOO_LARGE, "number too large")
                .with_primary(span, "this does not fit in a 64-bit float")
                .with_note(format!("the largest finite value is about {:e}", f64::MAX)),
        ),
    }
}

/// `ident prime*`: a name and its number of derivative marks.
fn var(pair: Pair<Rule>) -> Node {
    let span = Span::from(pair.as_span());
    let mut children = pair.into_inner();
    let name = match children.next() {
        Some(name) => ident(name),
        None => Ident {
            name: String::new(),
            span,
        },
    };
    // Saturates: `check` rejects orders far below u32::MAX anyway.
    let primes = u32::try_from(children.count()).unwrap_or(u32::MAX);
    Node::leaf(ExprKind::Var { name, primes }, span)
}

fn call(pair: Pair<Rule>) -> Converted<Node> {
    let span = Span::from(pair.as_span());
    let mut children = Children::of(pair);
    let name = ident(children.expect(Rule::ident)?);
    let Some(func) = Builtin::from_name(&name.name) else {
        return Err(unknown_function(&name));
    };
    let mut args = Vec::new();
    for arg in children {
        args.push(expression(arg)?);
    }
    if args.len() != func.arity() {
        let wanted = match func.arity() {
            1 => "one argument".to_string(),
            n => format!("{n} arguments"),
        };
        return Err(Diagnostic::error(
            codes::WRONG_ARGUMENT_COUNT,
            format!("`{}` takes {wanted}, not {}", name.name, args.len()),
        )
        .with_primary(span, format!("{} given here", args.len())));
    }
    let level = level_of(&args);
    let kind = ExprKind::Call {
        func,
        func_span: name.span,
        args: args.into_iter().map(|a| a.expr).collect(),
    };
    deeper(kind, span, level, name.span)
}

fn unknown_function(name: &Ident) -> Diagnostic {
    let diagnostic = Diagnostic::error(
        codes::UNKNOWN_FUNCTION,
        format!("unknown function `{}`", name.name),
    )
    .with_primary(name.span, "not a function of the language");
    let names = Builtin::names();
    match crate::suggest::closest(&name.name, names.iter().copied()) {
        Some(close) => diagnostic.with_help(format!("did you mean `{close}`?")),
        None => diagnostic.with_help(format!("the functions are {}", names.join(", "))),
    }
}

/// Wraps `node` in the minus signs `negs` (innermost last).
fn negate(negs: Vec<Span>, mut node: Node) -> Converted<Node> {
    for neg_span in negs.into_iter().rev() {
        let span = neg_span.to(node.expr.span);
        let level = (node.depth, node.height);
        node = deeper(ExprKind::Neg(Box::new(node.expr)), span, level, neg_span)?;
    }
    Ok(node)
}

fn binary(op: BinOp, op_span: Span, lhs: Node, rhs: Node) -> Converted<Node> {
    let span = lhs.expr.span.to(rhs.expr.span);
    let depth = lhs.depth.max(rhs.depth);
    let height = lhs.height.max(rhs.height);
    let kind = ExprKind::Binary {
        op,
        lhs: Box::new(lhs.expr),
        rhs: Box::new(rhs.expr),
    };
    node_at(kind, span, depth + 1, height + 1, op_span)
}

/// One more link of a left-folded chain (`acc op rhs`): the chain stays at
/// its nesting level (the 1,275 terms of a 50-link pendulum's potential are
/// one level), its tree grows by one.
fn chain(op: BinOp, op_span: Span, acc: Node, rhs: Node) -> Converted<Node> {
    let span = acc.expr.span.to(rhs.expr.span);
    let depth = acc.depth.max(rhs.depth + 1);
    let height = acc.height.max(rhs.height) + 1;
    let kind = ExprKind::Binary {
        op,
        lhs: Box::new(acc.expr),
        rhs: Box::new(rhs.expr),
    };
    node_at(kind, span, depth, height, op_span)
}

/// The largest depth and height among `nodes`.
fn level_of(nodes: &[Node]) -> (usize, usize) {
    nodes
        .iter()
        .fold((0, 0), |(d, h), n| (d.max(n.depth), h.max(n.height)))
}

/// A node one level above children of depth `child_depth` (and height
/// `child_height`).
fn deeper(kind: ExprKind, span: Span, child: (usize, usize), at: Span) -> Converted<Node> {
    node_at(kind, span, child.0 + 1, child.1 + 1, at)
}

/// A node of nesting `depth` and tree `height`, unless that crosses
/// [`MAX_EXPR_DEPTH`] or [`MAX_TREE_HEIGHT`] (reported at `at`).
fn node_at(kind: ExprKind, span: Span, depth: usize, height: usize, at: Span) -> Converted<Node> {
    if depth > MAX_EXPR_DEPTH {
        return Err(too_deep_expr(at));
    }
    if height > MAX_TREE_HEIGHT {
        return Err(too_long_chain(at));
    }
    Ok(Node {
        expr: Expr { kind, span },
        depth,
        height,
    })
}

/// The grammar guarantees the tree's shape; should it ever differ, this
/// reports it instead of panicking.
fn unexpected_tree(span: Span) -> Diagnostic {
    Diagnostic::error(codes::SYNTAX, "internal error: unexpected parse tree")
        .with_primary(span, "the parser could not convert this")
        .with_note("this is a bug in lagc; please report it with this file")
}

/// The children of a pair that carry meaning: punctuation and keywords,
/// which are named rules only for syntax error messages, are skipped.
struct Children<'i> {
    pairs: Pairs<'i, Rule>,
    parent_span: Span,
}

impl<'i> Children<'i> {
    fn of(pair: Pair<'i, Rule>) -> Self {
        Children {
            parent_span: pair.as_span().into(),
            pairs: pair.into_inner(),
        }
    }

    fn expect(&mut self, rule: Rule) -> Converted<Pair<'i, Rule>> {
        match self.next() {
            Some(pair) if pair.as_rule() == rule => Ok(pair),
            Some(pair) => Err(unexpected_tree(pair.as_span().into())),
            None => Err(unexpected_tree(self.parent_span)),
        }
    }
}

impl<'i> Iterator for Children<'i> {
    type Item = Pair<'i, Rule>;

    fn next(&mut self) -> Option<Self::Item> {
        self.pairs
            .by_ref()
            .find(|pair| !is_punctuation(pair.as_rule()))
    }
}

fn is_punctuation(rule: Rule) -> bool {
    is_statement_keyword(rule)
        || matches!(
            rule,
            Rule::semi
                | Rule::eq
                | Rule::comma
                | Rule::range
                | Rule::lparen
                | Rule::rparen
                | Rule::lbrace
                | Rule::rbrace
                | Rule::kw_position
                | Rule::kw_absolute
                | Rule::kw_relative
                | Rule::kw_velocity
                | Rule::kw_when
                | Rule::kw_for
                | Rule::kw_if
                | Rule::kw_then
                | Rule::kw_else
                | Rule::kw_and
                | Rule::kw_or
        )
}
