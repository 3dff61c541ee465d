"""The tasks of the paper: the multi-block world (``blocks``) and its planning driver
(``planning``); the cup task lives in ``cups``."""
