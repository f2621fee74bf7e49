"""`hmblur` and its subcommands: `main` builds the parser and runs one command; each
command is its own module that adds itself with `register(subparsers)`."""
