"""prsc's model library: the .prs files a spec imports by name (`from tabletop import *`), and
its arms' data (`<arm>.json`: the file an arm is read from and what the library adds to it,
prsc/user_assets/asset_fitting.py), shipped as package data so an installed prsc finds them
without the repository."""
