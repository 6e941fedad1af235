from robotkit.cli import main

raise SystemExit(main())
