from ..cli.compose import main

raise SystemExit(main())
