"""prsc's model library: the .prs files a spec imports by name (`from tabletop import *`),
shipped as package data so an installed prsc finds them without the repository."""
