"""Front end: lexer, AST and recursive-descent parser of the .pik language."""
from pik_gen.frontend.lexer import Token, tokenize
from pik_gen.frontend.parser import parse

__all__ = ["Token", "tokenize", "parse"]
