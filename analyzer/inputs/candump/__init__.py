"""candump text logs (-L and screen layouts): the fast block scan and the careful line parser."""
