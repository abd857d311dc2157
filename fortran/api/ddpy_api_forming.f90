!> f2py doorway of the forming problem (and of the static problem, a forming problem without
!> tools): one handle per problem in the core's handle table, made from the blank and its
!> constraints, given its tools one by one and its force-controlled tools; the Jacobian's
!> layout the core computes from them (ddpy_jacobian_layout), read back for the solver's
!> analysis; then, per increment trial, its settings, limits and start, where the tools
!> are and the pairs' law, by name; the trial itself; and what came of it. Node and
!> tool indices arrive 0-based (see ddpy_api.f90 for the conventions). Every call checks
!> what it is given against the problem before it stores it (the core writes where the
!> layout says), and refuses with a status of ddpy_handle_table (refusal_*) otherwise.
module ddpy_api_forming
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  use, intrinsic :: iso_fortran_env, only: int64
  use ddpy_kinds, only: wp
  use ddpy_handle_table, only: table, claim_handle, valid_handle, entry_blank, &
                               entry_surface, entry_problem, refusal_handle, refusal_size, &
                               refusal_index, refusal_full, refusal_value, refusal_order
  use ddpy_blank, only: blank_dofs
  use ddpy_forming_data, only: contact_tool, tool_set, pair_set, force_holds, contact_node, &
                               contact_gauss, max_face_order
  use ddpy_forming_problem, only: forming_problem, increment_answer, search_none, &
                                  search_energy, history_width
  use ddpy_forming, only: forming_contact
  use ddpy_global_search, only: memory_rows
  use ddpy_forming_newton, only: forming_increment, penetration_step, gmres, &
                                 hold_equations
  use ddpy_sparse, only: rows_fit, rows_build, sum_duplicates
  use ddpy_jacobian_layout, only: layout_build
  use ddpy_solid_assembly, only: solid_coo_count, solid_assemble, shell_modes
  implicit none
  private
  public :: api_problem_create, api_problem_add_tool, api_problem_set_penalty, &
            api_problem_set_holds, api_problem_layout_size, api_problem_layout, &
            api_problem_set_newton, api_problem_set_limits, &
            api_problem_set_state, api_problem_set_start, api_problem_set_tools, &
            api_problem_set_law, api_problem_increment, api_problem_report, &
            api_problem_history, api_problem_blank_answer, api_problem_pair_answer, &
            api_problem_contact, api_problem_evaluate, api_penetration_step, &
            api_krylov_solve

contains

  !> A problem of the blank behind handle blank (ddpy_api_solid) with the equation numbers
  !> eqn (0-based, -1 where a dof is fixed: the free ones numbered 0..nf - 1), the solid's
  !> tangent as its lower triangle when symmetric /= 0 (its slots per element the core's,
  !> solid_coo_count); no tools yet.
  subroutine api_problem_create(blank, nnode, eqn, symmetric, handle, status) &
    bind(C, name="ddpy_problem_create")
    integer(c_int), value, intent(in) :: blank, nnode, symmetric
    integer(c_int), intent(in) :: eqn(3, nnode)
    integer(c_int), intent(out) :: handle, status
    integer, allocatable :: counts(:)
    integer(int64) :: slots
    integer :: nf, ne, e
    handle = 0
    status = refusal_handle
    if (.not. valid_handle(blank, entry_blank)) return
    status = refusal_size
    if (nnode /= table(blank)%blank%nnode) return
    ne = table(blank)%blank%ne
    nf = count(eqn >= 0)
    status = refusal_index
    if (any(eqn < -1) .or. any(eqn >= nf)) return
    allocate(counts(ne))
    call solid_coo_count(nnode, ne, table(blank)%blank%conn, eqn, symmetric /= 0, counts)
    status = refusal_size  ! the tangent's slots must count in 32 bits
    slots = sum(int(counts, int64))
    if (slots > huge(1)) return
    status = refusal_full
    call claim_handle(entry_problem, handle)
    if (handle == 0) return
    allocate(table(handle)%problem, table(handle)%answer, table(handle)%report)
    associate (p => table(handle)%problem)
      p%blank = table(blank)%blank
      p%dofs%nf = nf
      p%dofs%k_slots = int(slots)
      p%dofs%symmetric = symmetric /= 0
      p%dofs%eqn = eqn
      p%dofs%fixed = eqn < 0
      allocate(p%dofs%offsets(ne + 1))
      p%dofs%offsets(1) = 0
      do e = 1, ne
        p%dofs%offsets(e + 1) = p%dofs%offsets(e) + counts(e)
      end do
      allocate(p%tools%tool(0), p%tools%faces(4, 0), p%tools%corner(4, 0), &
               p%tools%face_weight(0))
      p%tools%face_first = [0]
      allocate(p%pairs%node(0), p%pairs%patch_node(0), p%pairs%held(3, 0))
      p%pairs%tool_first = [0]
      p%pairs%patch_first = [0]
      allocate(p%holds%tool(0), p%holds%axis(3, 0), p%holds%source(0), p%holds%coef(0))
      p%holds%first = [0]
      ! No tools and no pairs: where the tools are and the pairs' law are set (empty).
      allocate(p%placement%positions(3, 0), p%placement%positions_n(3, 0), &
               p%placement%hold_force(0), p%law%on(0), p%law%r(0), p%law%mu(0), &
               p%law%traction_n(3, 0), p%law%pressure_n(0))
    end associate
    status = 0
  end subroutine api_problem_create

  !> The Jacobian's layout of problem p, computed when a tool or hold changed it; its
  !> structure by rows (for GMRES) is sorted again at the next trial.
  subroutine ensure_layout(p)
    type(forming_problem), intent(inout) :: p
    if (p%layout%built) return
    call layout_build(p%blank, p%dofs, p%tools, p%pairs, p%holds, p%layout)
    p%rows%n = -1
  end subroutine ensure_layout

  !> The problem behind handle, or refusal_handle in status.
  logical function problem_ok(handle, status)
    integer(c_int), intent(in) :: handle
    integer(c_int), intent(out) :: status
    problem_ok = valid_handle(handle, entry_problem)
    status = merge(0, refusal_handle, problem_ok)
  end function problem_ok

  !> One more tool, after those given: the surface behind handle surface (ddpy_api_search)
  !> with its contact (discretization: contact_node, contact_surface or contact_gauss;
  !> order: Gauss points per direction of its faces), its facing direction (faced /= 0:
  !> it has one; its penalties and barrier: problem_set_penalty), the blank's
  !> faces that face it (their nodes, 0-based; corner: each corner's slave index, -1 where
  !> not a slave; face_weight: the area each point stands for, order^2 per face, then one
  !> per slave for a Gauss-point tool), and its slaves (0-based nodes) with the nodes each
  !> one's law depends on (patch_first, 0-based starts; patch_node): its own node for
  !> node-to-surface contact, else every node of the faces around it. Refused after the
  !> force-controlled tools were set, or where the faces, slaves and patches do not fit.
  subroutine api_problem_add_tool(handle, surface, faced, facing, discretization, order, &
                                  nface, faces, ncorner, corner, npoint, face_weight, nslave, &
                                  slaves, patch_first, npatch, patch_node, status) &
    bind(C, name="ddpy_problem_add_tool")
    integer(c_int), value, intent(in) :: handle, surface, faced, discretization, order, &
                                         nface, ncorner, npoint, nslave, npatch
    real(c_double), intent(in) :: facing(3), face_weight(npoint)
    integer(c_int), intent(in) :: faces(4, nface), corner(4, ncorner), slaves(nslave), &
                                  patch_first(nslave + 1), patch_node(npatch)
    integer(c_int), intent(out) :: status
    type(contact_tool) :: tool
    integer :: points, nnode, p, f, q, qq, e
    logical :: found
    if (.not. problem_ok(handle, status)) return
    status = refusal_handle
    if (.not. valid_handle(surface, entry_surface)) return
    status = refusal_order
    if (table(handle)%problem%holds%nhold > 0) return
    status = refusal_value
    if (discretization < contact_node .or. discretization > contact_gauss .or. &
        order < 1 .or. order > max_face_order) return
    status = refusal_size
    points = order**2*nface
    if (discretization == contact_gauss) points = points + nslave
    if (npoint /= points .or. ncorner /= nface .or. patch_first(nslave + 1) /= npatch) return
    associate (p_ => table(handle)%problem)
      nnode = p_%blank%nnode
      status = refusal_index
      if (any(faces < 0) .or. any(faces >= nnode) .or. any(corner < -1) .or. &
          any(corner >= nslave)) return
      if (any(slaves < 0) .or. any(slaves >= nnode) .or. any(patch_node < 0) .or. &
          any(patch_node >= nnode)) return
      if (patch_first(1) /= 0 .or. any(patch_first(2:) <= patch_first(:nslave))) return
      if (discretization == contact_node) then
        ! A node-to-surface pair's law depends on its own node alone.
        do p = 1, nslave
          if (patch_first(p + 1) - patch_first(p) /= 1) return
          if (patch_node(patch_first(p + 1)) /= slaves(p)) return
        end do
      else
        ! The patch of a corner's slave holds every node of the face.
        do f = 1, nface
          do q = 1, 4
            if (corner(q, f) < 0) cycle
            p = corner(q, f) + 1
            if (faces(q, f) /= slaves(p)) return
            do qq = 1, 4
              found = .false.
              do e = patch_first(p) + 1, patch_first(p + 1)
                if (patch_node(e) == faces(qq, f)) found = .true.
              end do
              if (.not. found) return
            end do
          end do
        end do
      end if
      tool%surface = table(surface)%surface
      tool%faced = faced /= 0
      tool%facing = facing
      tool%discretization = discretization
      tool%order = order
      tool%first_point = p_%tools%npoint
      tool%npoint = npoint
      call append_tool(p_%tools, tool, faces, corner, face_weight)
      call append_pairs(p_%pairs, p_%dofs, slaves, patch_first, patch_node)
      p_%layout%built = .false.
      ! The per-increment parts sized for the old tools are set again.
      if (allocated(p_%placement%positions)) deallocate(p_%placement%positions)
      if (allocated(p_%law%on)) deallocate(p_%law%on)
      if (allocated(p_%start%force_n)) deallocate(p_%start%force_n)
    end associate
    status = 0
  end subroutine api_problem_add_tool

  !> tools with tool appended, and its faces, corners and points.
  pure subroutine append_tool(tools, tool, faces, corner, face_weight)
    type(tool_set), intent(inout) :: tools
    type(contact_tool), intent(in) :: tool
    integer, intent(in) :: faces(:, :), corner(:, :)
    real(wp), intent(in) :: face_weight(:)
    tools%tool = [tools%tool, tool]
    tools%ntool = tools%ntool + 1
    tools%faces = reshape([tools%faces, faces], [4, tools%nface + size(faces, 2)])
    tools%corner = reshape([tools%corner, corner], [4, tools%nface + size(faces, 2)])
    tools%nface = tools%nface + size(faces, 2)
    tools%face_first = [tools%face_first, tools%nface]
    tools%face_weight = [tools%face_weight, face_weight]
    tools%npoint = tools%npoint + size(face_weight)
  end subroutine append_tool

  !> pairs with a tool's slaves and their patches appended; a component of a slave that
  !> dofs fixes is held (its law lambda_c = 0).
  pure subroutine append_pairs(pairs, dofs, slaves, patch_first, patch_node)
    type(pair_set), intent(inout) :: pairs
    type(blank_dofs), intent(in) :: dofs
    integer, intent(in) :: slaves(:), patch_first(:), patch_node(:)
    integer :: k
    k = size(slaves)
    pairs%node = [pairs%node, slaves]
    pairs%patch_first = [pairs%patch_first, pairs%npatch + patch_first(2:)]
    pairs%patch_node = [pairs%patch_node, patch_node]
    pairs%held = reshape([pairs%held, merge(1, 0, dofs%eqn(:, slaves + 1) < 0)], &
                         [3, pairs%npair + k])
    pairs%npair = pairs%npair + k
    pairs%npatch = pairs%npatch + size(patch_node)
    pairs%tool_first = [pairs%tool_first, pairs%npair]
  end subroutine append_pairs

  !> Tool tool's (0-based) law of Gauss-point contact: its normal and tangential penalties
  !> (N/mm^3) and its barrier's depth (mm; negative: none) (see contact_tool); zero and
  !> none until set. Whether a tool has a barrier shapes the Jacobian's layout: once that
  !> is built, it cannot change (refusal_value).
  subroutine api_problem_set_penalty(handle, tool, normal_penalty, tangential_penalty, &
                                     barrier_depth, status) &
    bind(C, name="ddpy_problem_set_penalty")
    integer(c_int), value, intent(in) :: handle, tool
    real(c_double), value, intent(in) :: normal_penalty, tangential_penalty, barrier_depth
    integer(c_int), intent(out) :: status
    if (.not. problem_ok(handle, status)) return
    status = refusal_index
    if (tool < 0 .or. tool >= table(handle)%problem%tools%ntool) return
    associate (t => table(handle)%problem%tools%tool(tool + 1))
      status = refusal_value
      if (table(handle)%problem%layout%built .and. &
          ((t%barrier_depth >= 0.0_wp) .neqv. (barrier_depth >= 0.0_wp))) return
      t%normal_penalty = normal_penalty
      t%tangential_penalty = tangential_penalty
      t%barrier_depth = barrier_depth
    end associate
    status = 0
  end subroutine api_problem_set_penalty

  !> The force-controlled tools, after the tools: tool(k) (0-based) presses along axis(:, k).
  !> Each tool at most once. The entries of their rows and columns are the layout's.
  subroutine api_problem_set_holds(handle, nhold, tool, axis, status) &
    bind(C, name="ddpy_problem_set_holds")
    integer(c_int), value, intent(in) :: handle, nhold
    integer(c_int), intent(in) :: tool(nhold)
    real(c_double), intent(in) :: axis(3, nhold)
    integer(c_int), intent(out) :: status
    integer :: k
    if (.not. problem_ok(handle, status)) return
    associate (p => table(handle)%problem)
      status = refusal_index
      if (any(tool < 0) .or. any(tool >= p%tools%ntool)) return
      do k = 1, nhold
        if (count(tool == tool(k)) /= 1) return
      end do
      p%holds%nhold = nhold
      p%holds%tool = tool + 1
      p%holds%axis = axis
      p%layout%built = .false.
      if (allocated(p%placement%positions)) deallocate(p%placement%positions)
    end associate
    status = 0
  end subroutine api_problem_set_holds

  !> The size of the problem's Jacobian (ddpy_jacobian_layout): n unknowns, nvalues
  !> coordinate slots, of which k_slots the solid's tangent.
  subroutine api_problem_layout_size(handle, n, nvalues, k_slots, status) &
    bind(C, name="ddpy_problem_layout_size")
    integer(c_int), value, intent(in) :: handle
    integer(c_int), intent(out) :: n, nvalues, k_slots, status
    n = 0
    nvalues = 0
    k_slots = 0
    if (.not. problem_ok(handle, status)) return
    associate (p => table(handle)%problem)
      call ensure_layout(p)
      n = p%layout%n
      nvalues = p%layout%nvalues
      k_slots = p%layout%k_slots
    end associate
  end subroutine api_problem_layout_size

  !> The Jacobian's coordinate structure, the row and column (0-based) of each of its
  !> nvalues slots in the order the evaluations write them (ddpy_jacobian_layout): what
  !> the solver analyses.
  subroutine api_problem_layout(handle, nvalues, rows, cols, status) &
    bind(C, name="ddpy_problem_layout")
    integer(c_int), value, intent(in) :: handle, nvalues
    integer(c_int), intent(out) :: rows(nvalues), cols(nvalues), status
    rows = 0
    cols = 0
    if (.not. problem_ok(handle, status)) return
    associate (p => table(handle)%problem)
      call ensure_layout(p)
      status = refusal_size
      if (nvalues /= p%layout%nvalues) return
      rows = p%layout%rows
      cols = p%layout%cols
    end associate
    status = 0
  end subroutine api_problem_layout

  !> How the Newton loop runs the next trials (newton_settings, by name; reuse,
  !> search_memory and the line search search_*).
  subroutine api_problem_set_newton(handle, force_tolerance, displacement_tolerance, &
                                    max_iterations, floor, reuse, krylov_loose, &
                                    krylov_tight, krylov_last, krylov_max, krylov_keep, &
                                    line_search, whole_step, search_memory, status) &
    bind(C, name="ddpy_problem_set_newton")
    integer(c_int), value, intent(in) :: handle, max_iterations, reuse, krylov_max, &
                                         krylov_keep, line_search, search_memory
    real(c_double), value, intent(in) :: force_tolerance, displacement_tolerance, floor, &
                                         krylov_loose, krylov_tight, krylov_last, &
                                         whole_step
    integer(c_int), intent(out) :: status
    if (.not. problem_ok(handle, status)) return
    status = refusal_value
    if (max_iterations < 0 .or. krylov_max < 1 .or. .not. krylov_last >= 0.0_c_double .or. &
        line_search < search_none .or. line_search > search_energy) return
    associate (n => table(handle)%problem%newton)
      n%force_tolerance = force_tolerance
      n%displacement_tolerance = displacement_tolerance
      n%max_iterations = max_iterations
      n%floor = floor
      n%reuse = reuse /= 0
      n%krylov_loose = krylov_loose
      n%krylov_tight = krylov_tight
      n%krylov_last = krylov_last
      n%krylov_max = krylov_max
      n%krylov_keep = krylov_keep
      n%line_search = line_search
      n%whole_step = whole_step
      n%search_memory = search_memory /= 0
    end associate
    table(handle)%problem%has_newton = .true.
    status = 0
  end subroutine api_problem_set_newton

  !> The limits of the next trials and contact looks (increment_limits, by name; resting
  !> /= 0: the touching predictor closes the touching pairs of tools at rest).
  subroutine api_problem_set_limits(handle, reach, element_size, touching, resting, &
                                    penetration, min_step, yield_tolerance, size_ratio, &
                                    hold_step, status) bind(C, name="ddpy_problem_set_limits")
    integer(c_int), value, intent(in) :: handle, resting
    real(c_double), value, intent(in) :: reach, element_size, touching, penetration, &
                                         min_step, yield_tolerance, size_ratio, hold_step
    integer(c_int), intent(out) :: status
    if (.not. problem_ok(handle, status)) return
    status = refusal_value
    if (.not. (reach >= 0.0_wp .and. element_size > 0.0_wp)) return
    associate (l => table(handle)%problem%limits)
      l%reach = reach
      l%element_size = element_size
      l%touching = touching
      l%resting = resting /= 0
      l%penetration = penetration
      l%min_step = min_step
      l%yield_tolerance = yield_tolerance
      l%size_ratio = size_ratio
      l%hold_step = hold_step
    end associate
    table(handle)%problem%has_limits = .true.
    status = 0
  end subroutine api_problem_set_limits

  !> The converged state of the blank the next trials start from: its displacements u_ref
  !> and, per Gauss point, its material axes, stress, plastic strain, strain and
  !> backstress (nback = ne with mixed hardening, else any: not read).
  subroutine api_problem_set_state(handle, nnode, u_ref, ne, axes_old, stress_old, ep_old, &
                                   strain_old, nback, back_old, status) &
    bind(C, name="ddpy_problem_set_state")
    integer(c_int), value, intent(in) :: handle, nnode, ne, nback
    real(c_double), intent(in) :: u_ref(3, nnode), axes_old(3, 3, 8, ne), &
                                  stress_old(6, 8, ne), ep_old(8, ne), strain_old(6, 8, ne), &
                                  back_old(6, 8, nback)
    integer(c_int), intent(out) :: status
    if (.not. problem_ok(handle, status)) return
    associate (p => table(handle)%problem)
      status = refusal_size
      if (nnode /= p%blank%nnode .or. ne /= p%blank%ne) return
      p%start%u_ref = u_ref
      p%start%axes_old = axes_old
      p%start%stress_old = stress_old
      p%start%ep_old = ep_old
      p%start%strain_old = strain_old
      p%start%back_old = back_old
    end associate
    status = 0
  end subroutine api_problem_set_state

  !> Where the next trials start and what drives them: the converged displacements u_n
  !> and pair forces force_n, the nodal loads, the fixed dofs' values, and the start of
  !> the iterations (guess, where has_guess /= 0).
  subroutine api_problem_set_start(handle, nnode, u_n, external, prescribed, guess, &
                                   has_guess, npair, force_n, status) &
    bind(C, name="ddpy_problem_set_start")
    integer(c_int), value, intent(in) :: handle, nnode, has_guess, npair
    real(c_double), intent(in) :: u_n(3, nnode), external(3, nnode), prescribed(3, nnode), &
                                  guess(3, nnode), force_n(3, npair)
    integer(c_int), intent(out) :: status
    if (.not. problem_ok(handle, status)) return
    associate (p => table(handle)%problem)
      status = refusal_size
      if (nnode /= p%blank%nnode .or. npair /= p%pairs%npair) return
      p%start%u_n = u_n
      p%start%external = external
      p%start%prescribed = prescribed
      p%start%guess = guess
      p%start%has_guess = has_guess /= 0
      p%start%force_n = force_n
    end associate
    status = 0
  end subroutine api_problem_set_start

  !> Where the tools are in the next trials and looks (positions), where they were at the
  !> last converged increment (positions_n), and the force each force-controlled tool
  !> presses with (N).
  subroutine api_problem_set_tools(handle, ntool, positions, positions_n, nhold, hold_force, &
                                   status) bind(C, name="ddpy_problem_set_tools")
    integer(c_int), value, intent(in) :: handle, ntool, nhold
    real(c_double), intent(in) :: positions(3, ntool), positions_n(3, ntool), &
                                  hold_force(nhold)
    integer(c_int), intent(out) :: status
    if (.not. problem_ok(handle, status)) return
    associate (p => table(handle)%problem)
      status = refusal_size
      if (ntool /= p%tools%ntool .or. nhold /= p%holds%nhold) return
      p%placement%positions = positions
      p%placement%positions_n = positions_n
      p%placement%hold_force = hold_force
    end associate
    status = 0
  end subroutine api_problem_set_tools

  !> The pairs' law in the next trials and looks: which take part (on /= 0), their
  !> augmentation and friction, and each Gauss point's tangential traction and pressure
  !> multiplier at the last converged increment.
  subroutine api_problem_set_law(handle, npair, on, r, mu, ntraction, traction_n, npoint, &
                                 pressure_n, status) bind(C, name="ddpy_problem_set_law")
    integer(c_int), value, intent(in) :: handle, npair, ntraction, npoint
    integer(c_int), intent(in) :: on(npair)
    real(c_double), intent(in) :: r(npair), mu(npair), traction_n(3, ntraction), &
                                  pressure_n(npoint)
    integer(c_int), intent(out) :: status
    if (.not. problem_ok(handle, status)) return
    associate (p => table(handle)%problem)
      status = refusal_size
      if (npair /= p%pairs%npair .or. npoint /= p%tools%npoint .or. ntraction /= npoint) &
        return
      p%law%on = on
      p%law%r = r
      p%law%mu = mu
      p%law%traction_n = traction_n
      p%law%pressure_n = pressure_n
    end associate
    status = 0
  end subroutine api_problem_set_law

  !> Whether every part a contact look needs was set for the present tools and pairs.
  pure logical function ready_for_contact(p)
    type(forming_problem), intent(in) :: p
    ready_for_contact = p%has_limits .and. allocated(p%placement%positions) .and. &
                        allocated(p%law%on)
  end function ready_for_contact

  !> One increment trial of the problem (forming_increment) with the MUMPS instance behind
  !> solver (analysed for the problem's Jacobian): factored and reuse_next, the state of
  !> its factors, are updated; outcome says what came of it (problem_report,
  !> problem_history and, when converged, problem_blank_answer and problem_pair_answer
  !> give the rest). Refused (refusal_order) before the settings, limits, state, start,
  !> tools and law are set. The Jacobian's structure by rows (for GMRES; and a symmetric
  !> layout's entries, which its solver factorizes) is sorted at the first trial of a
  !> layout.
  subroutine api_problem_increment(handle, solver, factored, reuse_next, outcome, status) &
    bind(C, name="ddpy_problem_increment")
    integer(c_int), value, intent(in) :: handle, solver
    integer(c_int), intent(inout) :: factored, reuse_next
    integer(c_int), intent(out) :: outcome, status
    outcome = -1
    if (.not. problem_ok(handle, status)) return
    associate (p => table(handle)%problem, a => table(handle)%answer)
      status = refusal_order
      if (.not. (p%has_newton .and. ready_for_contact(p) .and. allocated(p%start%u_ref) .and. &
                 allocated(p%start%force_n))) return
      call ensure_layout(p)
      if (p%rows%n /= p%layout%n) then
        call rows_build(p%layout%n, p%layout%nvalues, p%layout%rows, p%layout%cols, &
                        p%dofs%symmetric, p%rows)
        if (p%dofs%symmetric) &
          call rows_build(p%layout%n, p%layout%nvalues, p%layout%rows, p%layout%cols, &
                          .false., p%entries)
      end if
      call size_answer(p, a)
      call forming_increment(p%blank, p%dofs, p%layout, p%rows, p%entries, p%tools, p%pairs, &
                             p%holds, p%newton, p%limits, p%start, p%placement, p%law, &
                             solver, factored, reuse_next, a, table(handle)%report)
      outcome = table(handle)%report%outcome
    end associate
    status = 0
  end subroutine api_problem_increment

  !> The answer's arrays sized for problem p.
  pure subroutine size_answer(p, a)
    type(forming_problem), intent(in) :: p
    type(increment_answer), intent(inout) :: a
    integer :: nnode, ne, npair, npoint
    nnode = p%blank%nnode
    ne = p%blank%ne
    npair = p%pairs%npair
    npoint = p%tools%npoint
    if (allocated(a%u)) then
      if (size(a%back, 3) == size(p%start%back_old, 3) .and. size(a%force, 2) == npair .and. &
          size(a%traction, 2) == npoint .and. size(a%shift) == p%holds%nhold) return
      deallocate(a%u, a%force, a%fint, a%stress, a%ep, a%strain, a%axes, a%back, a%state, &
                 a%gap, a%normal, a%traction, a%pressure, a%shift)
    end if
    allocate(a%u(3, nnode), a%force(3, npair), a%fint(3, nnode), a%stress(6, 8, ne), &
             a%ep(8, ne), a%strain(6, 8, ne), a%axes(3, 3, 8, ne), &
             a%back(6, 8, size(p%start%back_old, 3)), a%state(npair), a%gap(npair), &
             a%normal(3, npair), a%traction(3, npoint), a%pressure(npoint), &
             a%shift(p%holds%nhold))
  end subroutine size_answer

  !> What the last trial did (increment_report, by name): the element status and the
  !> element (1-based), the tool (0-based) that lost the blank, and so on.
  subroutine api_problem_report(handle, outcome, niter, evaluations, corrections, &
                                factorizations, krylov_iterations, fallbacks, assembly_time, &
                                contact_time, factorization_time, solve_time, &
                                element_status, element, solver_status, flipped, hold_tool, &
                                hold_reason, landing, residual, correction, status) &
    bind(C, name="ddpy_problem_report")
    integer(c_int), value, intent(in) :: handle
    integer(c_int), intent(out) :: outcome, niter, evaluations, corrections, factorizations, &
                                   krylov_iterations, fallbacks, element_status, element, &
                                   solver_status, flipped, hold_tool, hold_reason, status
    real(c_double), intent(out) :: assembly_time, contact_time, factorization_time, &
                                   solve_time, landing, residual, correction
    if (.not. problem_ok(handle, status)) return
    associate (r => table(handle)%report)
      outcome = r%outcome
      niter = r%niter
      evaluations = r%evaluations
      corrections = r%corrections
      factorizations = r%factorizations
      krylov_iterations = r%krylov_iterations
      fallbacks = r%fallbacks
      assembly_time = r%assembly_time
      contact_time = r%contact_time
      factorization_time = r%factorization_time
      solve_time = r%solve_time
      element_status = r%element_status
      element = r%element
      solver_status = r%solver_status
      flipped = r%flipped
      hold_tool = r%hold_tool - 1
      hold_reason = r%hold_reason
      landing = r%landing
      residual = r%residual
      correction = r%correction
    end associate
  end subroutine api_problem_report

  !> The last trial's first nhistory iterations (nhistory at most its niter): per iteration
  !> the rows history_* of increment_report%history (residuals, step, what switched).
  subroutine api_problem_history(handle, nhistory, history, status) &
    bind(C, name="ddpy_problem_history")
    integer(c_int), value, intent(in) :: handle, nhistory
    real(c_double), intent(out) :: history(history_width, nhistory)
    integer(c_int), intent(out) :: status
    history = 0.0_wp
    if (.not. problem_ok(handle, status)) return
    status = refusal_size
    if (.not. allocated(table(handle)%report%history)) return
    if (nhistory < 0 .or. nhistory > table(handle)%report%niter) return
    history = table(handle)%report%history(:, 1:nhistory)
    status = 0
  end subroutine api_problem_history

  !> The blank's part of the last converged trial's answer, into the given arrays.
  subroutine api_problem_blank_answer(handle, nnode, u, fint, ne, stress, ep, strain, axes, &
                                      nback, back, status) &
    bind(C, name="ddpy_problem_blank_answer")
    integer(c_int), value, intent(in) :: handle, nnode, ne, nback
    real(c_double), intent(inout) :: u(3, nnode), fint(3, nnode), stress(6, 8, ne), &
                                     ep(8, ne), strain(6, 8, ne), axes(3, 3, 8, ne), &
                                     back(6, 8, nback)
    integer(c_int), intent(out) :: status
    if (.not. problem_ok(handle, status)) return
    associate (a => table(handle)%answer)
      status = refusal_order
      if (.not. allocated(a%u)) return
      status = refusal_size
      if (nnode /= size(a%u, 2) .or. ne /= size(a%ep, 2) .or. nback /= size(a%back, 3)) &
        return
      u = a%u
      fint = a%fint
      stress = a%stress
      ep = a%ep
      strain = a%strain
      axes = a%axes
      back = a%back
    end associate
    status = 0
  end subroutine api_problem_blank_answer

  !> The pairs' part of the last converged trial's answer (npair pairs, npoint Gauss points
  !> and nhold force-controlled tools, as the problem has them): forces,
  !> contact states, gaps, normals, the Gauss points' tractions and pressures, and the
  !> force-controlled tools' displacements along their axes.
  subroutine api_problem_pair_answer(handle, npair, force, state, gap, normal, npoint, &
                                     traction, pressure, nhold, shift, status) &
    bind(C, name="ddpy_problem_pair_answer")
    integer(c_int), value, intent(in) :: handle, npair, npoint, nhold
    real(c_double), intent(out) :: force(3, npair), gap(npair), normal(3, npair), &
                                   traction(3, npoint), pressure(npoint), shift(nhold)
    integer(c_int), intent(out) :: state(npair), status
    force = 0.0_wp
    state = 0
    gap = 0.0_wp
    normal = 0.0_wp
    traction = 0.0_wp
    pressure = 0.0_wp
    shift = 0.0_wp
    if (.not. problem_ok(handle, status)) return
    associate (a => table(handle)%answer)
      status = refusal_order
      if (.not. allocated(a%u)) return
      status = refusal_size
      if (npair /= size(a%gap) .or. npoint /= size(a%pressure) .or. nhold /= size(a%shift)) &
        return
      force = a%force
      state = a%state
      gap = a%gap
      normal = a%normal
      traction = a%traction
      pressure = a%pressure
      shift = a%shift
    end associate
    status = 0
  end subroutine api_problem_pair_answer

  !> Contact of every pair at positions x, from the converged x_n, for the pair forces
  !> force, with the problem's tools, law and limits (see forming_contact): the law's rows
  !> and the pairs' forces in the equilibrium rows of residual (which hold fint -
  !> external), the contact entries of values (the coupling entries included; none when
  !> it is empty: a look at the gaps) and, with values, the rows and entries of the
  !> force-controlled tools; the
  !> pairs' states, gaps and normals, and the Gauss points' tractions and pressures.
  subroutine api_problem_contact(handle, nnode, x, x_n, npair, force, nrow, residual, &
                                 nvalues, values, state, gap, normal, npoint, traction, &
                                 pressure, status) bind(C, name="ddpy_problem_contact")
    integer(c_int), value, intent(in) :: handle, nnode, npair, nrow, nvalues, npoint
    real(c_double), intent(in) :: x(3, nnode), x_n(3, nnode), force(3, npair)
    real(c_double), intent(inout) :: residual(nrow), values(nvalues)
    integer(c_int), intent(out) :: state(npair), status
    real(c_double), intent(out) :: gap(npair), normal(3, npair), traction(3, npoint), &
                                   pressure(npoint)
    state = 0
    gap = 0.0_wp
    normal = 0.0_wp
    traction = 0.0_wp
    pressure = 0.0_wp
    if (.not. problem_ok(handle, status)) return
    associate (pb => table(handle)%problem)
      status = refusal_order
      if (.not. ready_for_contact(pb)) return
      call ensure_layout(pb)
      status = refusal_size
      if (nnode /= pb%blank%nnode .or. npair /= pb%pairs%npair .or. &
          npoint /= pb%tools%npoint .or. nrow /= pb%layout%n .or. &
          (nvalues /= pb%layout%nvalues .and. nvalues /= 0)) return
      call contact_equations(pb, nnode, x, x_n, npair, force, nrow, residual, nvalues, &
                             values, state, gap, normal, npoint, traction, pressure)
    end associate
    status = 0
  end subroutine api_problem_contact

  !> The contact's part of problem pb's equations (api_problem_contact), its sizes checked.
  subroutine contact_equations(pb, nnode, x, x_n, npair, force, nrow, residual, nvalues, &
                               values, state, gap, normal, npoint, traction, pressure)
    type(forming_problem), intent(in) :: pb
    integer, intent(in) :: nnode, npair, nrow, nvalues, npoint
    real(wp), intent(in) :: x(3, nnode), x_n(3, nnode), force(3, npair)
    real(wp), intent(inout) :: residual(nrow), values(nvalues)
    integer, intent(out) :: state(npair)
    real(wp), intent(out) :: gap(npair), normal(3, npair), traction(3, npoint), &
                             pressure(npoint)
    integer, allocatable :: lock(:), found(:)
    real(wp), allocatable :: dc_dt(:, :, :), lambda(:, :), stiffness(:), lumped(:, :), &
                             barrier_dt(:, :, :)
    real(wp) :: no_memory(memory_rows, 0)
    integer :: no_patch(0)
    integer :: p, nf
    nf = pb%dofs%nf
    allocate(lock(npair + npoint), found(npair + npoint), dc_dt(3, 3, npair), &
             lambda(3, npair), stiffness(pb%holds%nhold), lumped(3, npair), &
             barrier_dt(3, 3, npair))
    lock = 0  ! no pair held: a plain search
    call forming_contact(x, x_n, pb%dofs, pb%tools, pb%pairs, pb%law, &
                         pb%placement%positions, pb%placement%positions_n, pb%limits, &
                         pb%limits%touching, force, lock, 0, no_memory, no_patch, &
                         min(nvalues, pb%layout%contact_values), &
                         residual(1:nf + 3*npair), values, state, gap, normal, traction, &
                         pressure, found, dc_dt, lumped, barrier_dt)
    if (nvalues == 0) return
    values(pb%layout%k_slots + 1:pb%layout%k_slots + pb%layout%ncoupling) = &
      pb%layout%coupling
    if (pb%holds%nhold == 0) return
    ! The tools' equations as the Newton loop has them: a Gauss-point pair's lambda is
    ! F(x) (its law's residual is lambda - F).
    lambda = force
    do p = 1, npair
      if (pb%layout%eliminated(p)) lambda(:, p) = force(:, p) - residual(nf + 3*p - 2:nf + 3*p)
    end do
    call hold_equations(pb%dofs, pb%pairs, pb%law%on, pb%holds, pb%placement%hold_force, &
                        pb%layout%eliminated, pb%layout%barrier, lambda, lumped, dc_dt, &
                        barrier_dt, pb%layout%contact_values, residual(nf + 3*npair + 1:), &
                        values, stiffness)
  end subroutine contact_equations

  !> The equations of the Newton loop at displacements u and pair forces force, in an
  !> increment from the problem's converged state (problem_set_state; problem_set_start's
  !> u_n and loads) with its tools, law and limits (the touching predictor's gap of
  !> problem_set_limits closes the pairs within it): the residual (the free equilibrium
  !> rows fint - external less the pairs' forces, the pairs' laws, the force-controlled
  !> tools' balances), every Jacobian value in the layout's slots (the solid's tangent,
  !> then the contact's: problem_contact) and the pairs' states. A Gauss-point pair's law
  !> rows are lambda - F(x), as the loop's evaluation writes them before it eliminates the
  !> multiplier. element_status, element (1-based): an element that failed (nothing else
  !> is then written).
  subroutine api_problem_evaluate(handle, nnode, u, npair, force, nrow, residual, nvalues, &
                                  values, state, element_status, element, status) &
    bind(C, name="ddpy_problem_evaluate")
    integer(c_int), value, intent(in) :: handle, nnode, npair, nrow, nvalues
    real(c_double), intent(in) :: u(3, nnode), force(3, npair)
    real(c_double), intent(out) :: residual(nrow), values(nvalues)
    integer(c_int), intent(out) :: state(npair), element_status, element, status
    real(wp), allocatable :: fint(:, :), kdu(:, :), dp(:, :), stress(:, :, :), ep(:, :), &
                             strain(:, :, :), axes(:, :, :, :), back(:, :, :), &
                             alpha_in(:, :), alpha(:, :), gap(:), normal(:, :), &
                             traction(:, :), pressure(:)
    integer :: a, c, ne, nback
    residual = 0.0_wp
    values = 0.0_wp
    state = 0
    element_status = 0
    element = 0
    if (.not. problem_ok(handle, status)) return
    associate (p => table(handle)%problem)
      status = refusal_order
      if (.not. (ready_for_contact(p) .and. allocated(p%start%u_ref) .and. &
                 allocated(p%start%u_n))) return
      call ensure_layout(p)
      status = refusal_size
      if (nnode /= p%blank%nnode .or. npair /= p%pairs%npair .or. nrow /= p%layout%n .or. &
          nvalues /= p%layout%nvalues) return
      ne = p%blank%ne
      nback = size(p%start%back_old, 3)
      allocate(fint(3, nnode), kdu(3, nnode), dp(3, nnode), stress(6, 8, ne), ep(8, ne), &
               strain(6, 8, ne), axes(3, 3, 8, ne), back(6, 8, nback), &
               alpha_in(shell_modes, ne), alpha(shell_modes, ne), gap(npair), &
               normal(3, npair), traction(3, p%tools%npoint), pressure(p%tools%npoint))
      alpha_in = 0.0_wp
      dp = 0.0_wp
      back = p%start%back_old
      call solid_assemble(nnode, p%blank%x0, ne, p%blank%conn, p%blank%kind, p%start%u_ref, &
                          u, p%blank%props, p%start%axes_old, p%start%stress_old, &
                          p%start%ep_old, p%start%strain_old, nback, p%start%back_old, &
                          alpha_in, p%dofs%eqn, p%dofs%symmetric, .true., p%dofs%offsets, &
                          p%layout%k_slots, values(1:p%layout%k_slots), .false., dp, fint, &
                          kdu, stress, ep, strain, axes, back, alpha, element_status, element)
      status = 0
      if (element_status /= 0) return
      do a = 1, nnode
        do c = 1, 3
          if (p%dofs%eqn(c, a) >= 0) residual(p%dofs%eqn(c, a) + 1) = fint(c, a) - &
                                                                   p%start%external(c, a)
        end do
      end do
      call contact_equations(p, nnode, p%blank%x0 + u, p%blank%x0 + p%start%u_n, npair, &
                             force, nrow, residual, nvalues, values, state, gap, normal, &
                             p%tools%npoint, traction, pressure)
    end associate
  end subroutine api_problem_evaluate

  !> The step length the Newton loop's penetration limit allows (see penetration_step).
  subroutine api_penetration_step(nnode, npair, du, pair_node, on, state, gap, normal, &
                                  room_depth, min_step, step) &
    bind(C, name="ddpy_penetration_step")
    integer(c_int), value, intent(in) :: nnode, npair
    real(c_double), value, intent(in) :: room_depth, min_step
    real(c_double), intent(in) :: du(3, nnode), gap(npair), normal(3, npair)
    integer(c_int), intent(in) :: pair_node(npair), on(npair), state(npair)
    real(c_double), intent(out) :: step
    step = -1.0_wp  ! a pair's node out of range
    if (any(pair_node < 0) .or. any(pair_node >= nnode)) return
    step = penetration_step(nnode, npair, du, pair_node, on, state, gap, normal, room_depth, &
                            min_step)
  end subroutine api_penetration_step

  !> The Newton loop's GMRES: the correction x of J x = f from x0 = M^-1 f (J the
  !> coordinate values summed into the rows row_start, col, sources, source_start, 0-based:
  !> ddpy.core.linalg.row_structure; M the factors held by the MUMPS instance handle; W the
  !> weights): see gmres. converged is 1 or 0; status < 0 a MUMPS solve failed, 1 an index
  !> out of range.
  subroutine api_krylov_solve(n, nvalues, values, ncsr, row_start, col, nsrc, sources, &
                              source_start, weight, handle, f, x0, tol, m, x, k, converged, &
                              status) bind(C, name="ddpy_krylov_solve")
    integer(c_int), value, intent(in) :: n, nvalues, ncsr, nsrc, handle, m
    real(c_double), value, intent(in) :: tol
    integer(c_int), intent(in) :: row_start(n + 1), col(ncsr), sources(nsrc), &
                                  source_start(ncsr + 1)
    real(c_double), intent(in) :: values(nvalues), weight(n), f(n), x0(n)
    real(c_double), intent(out) :: x(n)
    integer(c_int), intent(out) :: k, converged, status
    real(wp), allocatable :: entry(:)
    logical :: done
    x = 0.0_wp
    k = 0
    converged = 0
    status = 1
    if (.not. rows_fit(n, ncsr, nsrc, nvalues, row_start, col, sources, source_start) .or. &
        m < 1 .or. any(weight <= 0.0_wp)) return
    allocate(entry(ncsr))
    call sum_duplicates(nvalues, ncsr, values, sources, source_start, entry)
    call gmres(n, row_start, ncsr, col, entry, weight, handle, f, x0, tol, m, x, k, done, &
               status)
    converged = merge(1, 0, done)
  end subroutine api_krylov_solve

end module ddpy_api_forming
