"""Recursive-descent parser of .pik files: one method per grammar rule.

The grammar rule each method implements is written in the comment above it.
Statements end at line ends; blank lines, comments and pragmas may appear
anywhere between them.
"""
from __future__ import annotations

from pik_gen.diagnostics import Span, error
from pik_gen.frontend import ast
from pik_gen.frontend.lexer import Token, tokenize
from pik_gen.frontend.names import (MAX_EXPR_DEPTH, MAX_IF_DEPTH, MAX_TREE_DEPTH, cxx_name_problem,
                                    reserved_problem)
from pik_gen.types import parse_type_name

ROLES = ("EPI", "EPJ", "FORCE")
ASSIGN_OPS = ("=", "+=", "-=", "*=", "/=")
COMPARISONS = ("==", "!=", "<", ">", "<=", ">=")


def _describe(tok: Token) -> str:
    if tok.kind == "newline":
        return "end of line"
    if tok.kind == "eof":
        return "end of file"
    return f"'{tok.text}'"


def check_tree_depth(e: ast.Expr) -> None:
    """An expression tree deeper than MAX_TREE_DEPTH (long operator chains such as
    a + a + ... nest too) is a located error; measured without recursion."""
    stack = [(e, 1)]
    while stack:
        node, d = stack.pop()
        if d > MAX_TREE_DEPTH:
            raise error(node.span, f"expression more than {MAX_TREE_DEPTH} operations deep; "
                        "split it with intermediate variables")
        for child in _children(node):
            stack.append((child, d + 1))


def _children(node: ast.Expr) -> tuple[ast.Expr, ...]:
    if isinstance(node, ast.Binary):
        return (node.left, node.right)
    if isinstance(node, ast.Unary):
        return (node.operand,)
    if isinstance(node, ast.Component):
        return (node.base,)
    if isinstance(node, ast.Call):
        return node.args
    return ()


class Parser:
    def __init__(self, tokens: list[Token], file: str) -> None:
        self.toks = tokens
        self.pos = 0
        self.file = file
        self.depth = 0     # expression nesting (MAX_EXPR_DEPTH)
        self.if_depth = 0  # if/elsif nesting (MAX_IF_DEPTH)

    # ----- token helpers -----
    def peek(self, k: int = 0) -> Token:
        return self.toks[min(self.pos + k, len(self.toks) - 1)]

    def at(self, kind: str, text: str | None = None, k: int = 0) -> bool:
        t = self.peek(k)
        return t.kind == kind and (text is None or t.text == text)

    def at_op(self, *ops: str) -> bool:
        return self.peek().kind == "op" and self.peek().text in ops

    def advance(self) -> Token:
        t = self.peek()
        self.pos = min(self.pos + 1, len(self.toks) - 1)
        return t

    def expect(self, kind: str, text: str | None, what: str) -> Token:
        if not self.at(kind, text):
            t = self.peek()
            raise error(t.span, f"expected {what}, found {_describe(t)}")
        return self.advance()

    def end_of_line(self, after: str) -> None:
        if not self.at("newline"):
            t = self.peek()
            raise error(t.span, f"unexpected {_describe(t)} after {after}; expected end of line")
        self.advance()

    def skip_blank(self) -> None:
        while self.at("newline"):
            self.advance()

    # file := { decl | table | function | pragma | statement | NEWLINE } EOF
    def module(self) -> ast.Module:
        decls: list = []
        functions: list[ast.Function] = []
        body: list[ast.Stmt] = []
        while True:
            self.skip_blank()
            t = self.peek()
            if t.kind == "eof":
                break
            if t.kind == "keyword" and t.text in ROLES and not self.at("op", ".", 1):
                decls.append(self.member_decl())
            elif t.kind == "ident" and parse_type_name(t.text) is not None and self.at("ident", None, 1):
                decls.append(self.param_decl())
            elif t.kind == "ident" and self.at("op", "=", 1) and self.at("op", "{", 2):
                decls.append(self.table_decl())
            elif t.kind == "keyword" and t.text == "function":
                functions.append(self.function())
            else:
                body.append(self.statement())
        return ast.Module(self.file, tuple(decls), tuple(functions), tuple(body))

    # member_decl := ('EPI'|'EPJ'|'FORCE') ['local'] TYPE IDENT [':' IDENT] NEWLINE
    def member_decl(self) -> ast.MemberDecl:
        role = self.advance()
        local = False
        if self.at("keyword", "local"):
            self.advance()
            local = True
        ty = self.type_name()
        name = self.expect("ident", None, "a name after the type")
        self.check_name(name, "")
        member, member_tok = name.text, name
        if self.at_op(":"):
            self.advance()
            if local:
                raise error(self.peek().span, "a 'local' declaration has no ':member' binding")
            member_tok = self.expect("ident", None, "a member name after ':'")
            member = member_tok.text
        if not local:
            self.check_name(member_tok, "member name")
        if role.text == "FORCE" and local:
            raise error(role.span, "'local' is only for EPI and EPJ (FORCE values are accumulated)")
        self.end_of_line("a declaration")
        return ast.MemberDecl(role.text, local, ty.text, name.text, member, role.span, ty.span)

    def type_name(self) -> Token:
        t = self.peek()
        if t.kind != "ident" or parse_type_name(t.text) is None:
            raise error(t.span, f"expected a type (F64, F32, F16, S64, S32, U64, U32, F64vec, ...), found {_describe(t)}")
        return self.advance()

    # param_decl := TYPE IDENT NEWLINE
    def param_decl(self) -> ast.ParamDecl:
        ty = self.type_name()
        name = self.expect("ident", None, "a parameter name")
        self.check_name(name, "parameter name")
        self.end_of_line("a parameter declaration")
        return ast.ParamDecl(ty.text, name.text, name.span, ty.span)

    # table_decl := IDENT '=' '{' number { ',' number } '}' NEWLINE
    def table_decl(self) -> ast.TableDecl:
        name = self.advance()
        self.advance()
        self.advance()
        values: list[ast.Number] = []
        while True:
            while self.at("newline"):
                self.advance()
            neg = False
            if self.at_op("-"):
                neg = True
                self.advance()
            t = self.peek()
            if t.kind not in ("int", "float"):
                raise error(t.span, f"expected a number in table '{name.text}', found {_describe(t)}")
            self.advance()
            values.append(ast.Number(("-" if neg else "") + t.text, t.kind == "float", t.span))
            while self.at("newline"):
                self.advance()
            if self.at_op(","):
                self.advance()
                continue
            self.expect("op", "}", "',' or '}' in a table")
            break
        self.end_of_line("a table")
        return ast.TableDecl(name.text, tuple(values), name.span)

    # function := 'function' IDENT '(' [IDENT {',' IDENT}] ')' NEWLINE
    #             { statement } 'return' expr NEWLINE 'end'
    def function(self) -> ast.Function:
        kw = self.advance()
        name = self.expect("ident", None, "a function name")
        self.expect("op", "(", "'(' after the function name")
        params: list[str] = []
        if not self.at_op(")"):
            while True:
                p = self.expect("ident", None, "a parameter name")
                if p.text in params:
                    raise error(p.span, f"duplicate parameter '{p.text}' of function '{name.text}'")
                params.append(p.text)
                if not self.at_op(","):
                    break
                self.advance()
        self.expect("op", ")", "')' after the function parameters")
        self.end_of_line("the function header")
        body: list[ast.Stmt] = []
        while True:
            self.skip_blank()
            if self.at("keyword", "return"):
                break
            if self.at("eof") or self.at("keyword", "end") or self.at("keyword", "function"):
                raise error(self.peek().span, f"function '{name.text}' needs 'return EXPR' before its 'end'")
            body.append(self.statement())
        self.advance()
        result = self.expression()
        self.end_of_line("the return expression")
        self.skip_blank()
        if not (self.at("keyword", "end") or self.at("keyword", "endif")):
            raise error(self.peek().span, f"expected 'end' to close function '{name.text}', found {_describe(self.peek())}")
        self.advance()
        self.end_of_line("'end'")
        return ast.Function(name.text, tuple(params), tuple(body), result, Span(kw.span.file, kw.span.line, kw.span.col, 8))

    # statement := pragma | if_stmt | assignment
    def statement(self) -> ast.Stmt:
        t = self.peek()
        if t.kind == "pragma":
            self.advance()
            self.end_of_line("a pragma")
            return ast.Pragma(t.text, t.span)
        if t.kind == "keyword" and t.text == "if":
            return self.if_stmt()
        if t.kind == "keyword" and t.text in ("elsif", "else", "endif", "end"):
            raise error(t.span, f"'{t.text}' without a matching 'if'")
        if t.kind == "keyword" and t.text in ROLES and not self.at("op", ".", 1):
            raise error(t.span, "declarations must be at top level, not inside 'if' or 'function'")
        return self.assignment()

    # if_stmt := 'if' expr NEWLINE block { 'elsif' expr NEWLINE block }
    #            [ 'else' NEWLINE block ] ( 'endif' | 'end' )
    def if_stmt(self) -> ast.If:
        kw = self.advance()
        self.if_depth += 1
        try:
            if self.if_depth > MAX_IF_DEPTH:
                raise error(kw.span, f"'if'/'elsif' nested more than {MAX_IF_DEPTH} levels deep")
            return self._if_rest(kw)
        finally:
            self.if_depth -= 1

    def _if_rest(self, kw: Token) -> ast.If:
        cond = self.expression()
        self.end_of_line("the 'if' condition")
        body = self.block(kw)
        orelse: tuple[ast.Stmt, ...] = ()
        t = self.peek()
        if t.text == "elsif":
            # `elsif` is an `if` nested in the else branch; it shares this if's terminator.
            orelse = (self.if_stmt(),)
            return ast.If(cond, body, orelse, kw.span)
        if t.text == "else":
            self.advance()
            self.end_of_line("'else'")
            orelse = self.block(kw)
            t = self.peek()
            if t.text in ("elsif", "else"):
                raise error(t.span, f"'{t.text}' after 'else'")
        self.advance()  # endif | end
        self.end_of_line(f"'{t.text}'")
        return ast.If(cond, body, orelse, kw.span)

    # block := { statement } (stops before elsif | else | endif | end)
    def block(self, opener: Token) -> tuple[ast.Stmt, ...]:
        stmts: list[ast.Stmt] = []
        while True:
            self.skip_blank()
            t = self.peek()
            if t.kind == "keyword" and t.text in ("elsif", "else", "endif", "end"):
                return tuple(stmts)
            if t.kind == "eof" or (t.kind == "keyword" and t.text in ("function", "return")):
                raise error(opener.span, "'if' is never closed (expected 'endif' or 'end')")
            stmts.append(self.statement())

    # assignment := lvalue ('=' | '+=' | '-=' | '*=' | '/=') expr NEWLINE
    # lvalue     := IDENT | ROLE '.' IDENT | lvalue '.' IDENT
    def assignment(self) -> ast.Assign:
        start = self.peek()
        if start.kind not in ("ident", "keyword") or (start.kind == "keyword" and start.text not in ROLES):
            raise error(start.span, f"expected a statement, found {_describe(start)}")
        target = self.postfix()
        if isinstance(target, ast.Name):
            self.check_name(start, "")
        if not isinstance(target, (ast.Name, ast.RoleMember, ast.Component)):
            raise error(start.span, "the left side of an assignment must be a name or a member")
        if not self.at_op(*ASSIGN_OPS):
            t = self.peek()
            raise error(t.span, f"expected an assignment ('=', '+=', '-=', '*=', '/='), found {_describe(t)}")
        op = self.advance()
        value = self.expression()
        self.end_of_line("the statement")
        return ast.Assign(target, op.text, value, op.span)

    # expr := or
    def expression(self) -> ast.Expr:
        self.depth += 1
        try:
            if self.depth > MAX_EXPR_DEPTH:
                raise error(self.peek().span, f"expression nested more than {MAX_EXPR_DEPTH} levels deep "
                            "(parentheses, calls); split it with intermediate variables")
            e = self.logic_or()
        finally:
            self.depth -= 1
        if self.depth == 0:
            check_tree_depth(e)
        return e

    def check_name(self, tok: Token, what: str) -> None:
        """A C++ keyword as a parameter or member name, or a reserved identifier anywhere."""
        why = cxx_name_problem(tok.text, what) if what else reserved_problem(tok.text)
        if why:
            raise error(tok.span, why)

    # or := and { '||' and }
    def logic_or(self) -> ast.Expr:
        e = self.logic_and()
        while self.at_op("||"):
            op = self.advance()
            e = ast.Binary("||", e, self.logic_and(), op.span)
        return e

    # and := comparison { '&&' comparison }
    def logic_and(self) -> ast.Expr:
        e = self.comparison()
        while self.at_op("&&"):
            op = self.advance()
            e = ast.Binary("&&", e, self.comparison(), op.span)
        return e

    # comparison := additive [ ('=='|'!='|'<'|'>'|'<='|'>=') additive ]
    def comparison(self) -> ast.Expr:
        e = self.additive()
        if self.at_op(*COMPARISONS):
            op = self.advance()
            e = ast.Binary(op.text, e, self.additive(), op.span)
            if self.at_op(*COMPARISONS):
                raise error(self.peek().span, "comparisons cannot be chained; combine them with '&&'")
        return e

    # additive := term { ('+'|'-') term }
    def additive(self) -> ast.Expr:
        e = self.term()
        while self.at_op("+", "-"):
            op = self.advance()
            e = ast.Binary(op.text, e, self.term(), op.span)
        return e

    # term := cross { ('*'|'/') cross }        (vec * vec is the dot product)
    def term(self) -> ast.Expr:
        e = self.cross()
        while self.at_op("*", "/"):
            op = self.advance()
            e = ast.Binary(op.text, e, self.cross(), op.span)
        return e

    # cross := unary { '^' unary }             (vec ^ vec is the cross product)
    def cross(self) -> ast.Expr:
        e = self.unary()
        while self.at_op("^"):
            op = self.advance()
            e = ast.Binary("^", e, self.unary(), op.span)
        return e

    # unary := ('-' | '+' | '!') unary | postfix
    def unary(self) -> ast.Expr:
        if self.at_op("-", "+", "!"):
            op = self.advance()
            self.depth += 1
            try:
                if self.depth > MAX_EXPR_DEPTH:
                    raise error(op.span, f"more than {MAX_EXPR_DEPTH} nested unary operators and parentheses")
                return ast.Unary(op.text, self.unary(), op.span)
            finally:
                self.depth -= 1
        return self.postfix()

    # postfix := primary { '.' IDENT }
    def postfix(self) -> ast.Expr:
        e = self.primary()
        while self.at_op("."):
            self.advance()
            t = self.peek()
            if t.kind != "ident":
                raise error(t.span, f"expected a member or component name after '.', found {_describe(t)}")
            self.advance()
            if isinstance(e, ast.Name) and e.name in ROLES:
                e = ast.RoleMember(e.name, t.text, e.span)
            else:
                e = ast.Component(e, t.text, t.span)
        if isinstance(e, ast.Name) and e.name in ROLES:
            raise error(e.span, f"'{e.name}' must be followed by '.member'")
        return e

    # primary := NUMBER | IDENT [ '(' [expr {',' expr}] ')' ] | ROLE | '(' expr ')'
    def primary(self) -> ast.Expr:
        t = self.peek()
        if t.kind in ("int", "float"):
            self.advance()
            return ast.Number(t.text, t.kind == "float", t.span)
        if t.kind == "keyword" and t.text in ROLES:
            self.advance()
            if self.at_op("["):
                raise error(self.peek().span, f"indexing '{t.text}[...]' is not supported; use {t.text}.member")
            return ast.Name(t.text, t.span)
        if t.kind == "ident":
            self.advance()
            if self.at_op("("):
                self.advance()
                args: list[ast.Expr] = []
                if not self.at_op(")"):
                    while True:
                        args.append(self.expression())
                        if not self.at_op(","):
                            break
                        self.advance()
                self.expect("op", ")", f"',' or ')' in the call of '{t.text}'")
                return ast.Call(t.text, tuple(args), t.span)
            return ast.Name(t.text, t.span)
        if t.kind == "op" and t.text == "(":
            self.advance()
            e = self.expression()
            self.expect("op", ")", "')'")
            return e
        raise error(t.span, f"expected an expression, found {_describe(t)}")


def parse(source: str, file: str) -> ast.Module:
    """Parse a whole .pik file; raises CompileError with a located diagnostic."""
    return Parser(tokenize(source, file), file).module()
