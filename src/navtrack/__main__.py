from navtrack.cli import main

raise SystemExit(main())
