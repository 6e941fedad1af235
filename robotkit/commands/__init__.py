"""The verbs of the command line, one module each (``run(args)``): the only modules that chain
stages (load, build, check, picture, import).  ``inputs`` says what a PATH is for all of them."""
