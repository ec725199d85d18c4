"""The docs' tooling: the generators of the docs' tables and numbers (:mod:`.generators`) and the
command that fills the pages with them and checks them (:mod:`.pages`, ``mimo-radar-bench
docs``). It works on the ``docs/`` folder of a source checkout, so it is not part of the
installed package (pyproject.toml leaves it out of the wheel)."""

#: Marks this package as mimo-radar-env's.
DISTRIBUTION = "mimo-radar-env"
