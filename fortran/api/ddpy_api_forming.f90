!> f2py doorway of the forming problem's contact (see ddpy_api.f90 for the conventions and
!> ddpy_forming for the arguments). Node indices arrive 0-based.
module ddpy_api_forming
  use, intrinsic :: iso_c_binding, only: c_int, c_double
  use ddpy_kinds, only: wp
  use ddpy_forming, only: forming_contact, tool_fields, max_face_order, surface_gauss
  use ddpy_forming_newton, only: forming_increment, newton_settings, newton_integer_settings, &
                                 penetration_step, gmres, hold_equations
  use ddpy_material, only: material_prop_count
  use ddpy_solid_assembly, only: kind_hexahedron, kind_solid_shell
  implicit none
  private
  public :: api_forming_contact, api_forming_increment, api_static_increment, &
            api_penetration_step, api_krylov_solve

contains

  !> Whether the packed tools, the pairs and the Jacobian layout fit the arrays they index
  !> (the core writes where they say): node indices in range, tool and face ranges
  !> increasing, each tool's patches, tree and grid within the packed arrays, each pair's
  !> patch its own node (node-to-surface) or holding every node of the tool's faces at
  !> its node (surface-to-surface), and nvalues the solid's k_slots plus the contact
  !> blocks of the layout (or 0: no Jacobian).
  pure logical function layout_ok(nnode, ntool, table, ncoef, ndeg, ntri, ntree, nframe, &
                                  nstart, ngrid, grid_start, face_first, nface, faces, &
                                  corner, npoint, npair, tool_first, pair_node, npatch, &
                                  patch_first, patch_node, eqn, k_slots, nvalues) result(ok)
    integer(c_int), intent(in) :: nnode, ntool, ncoef, ndeg, ntri, ntree, nframe, nstart, &
                                  ngrid, nface, npoint, npair, npatch, k_slots, nvalues
    integer(c_int), intent(in) :: table(tool_fields, ntool), grid_start(nstart), &
                                  face_first(ntool + 1), faces(4, nface), corner(4, nface), &
                                  tool_first(ntool + 1), pair_node(npair), &
                                  patch_first(npair + 1), patch_node(npatch), eqn(3, nnode)
    integer :: t, np_, po, first, last, coupled, p, f, q, qq, e, entries, points, rows
    logical :: found
    ok = .false.
    if (any(pair_node < 0) .or. any(pair_node >= nnode)) return
    if (any(patch_node < 0) .or. any(patch_node >= nnode)) return
    if (patch_first(1) /= 0 .or. patch_first(npair + 1) /= npatch) return
    if (any(patch_first(2:) <= patch_first(:npair))) return
    if (any(faces < 0) .or. any(faces >= nnode) .or. any(corner < -1)) return
    if (tool_first(1) /= 0 .or. tool_first(ntool + 1) /= npair) return
    if (face_first(1) /= 0 .or. face_first(ntool + 1) /= nface) return
    ! Each tool's n x n points per face, one tool after another, fill the point arrays; a
    ! Gauss-point tool's are followed by one per slave (its barrier).
    points = 0
    do t = 1, ntool
      if (table(12, t) < 1 .or. table(12, t) > max_face_order .or. table(13, t) /= points) &
        return
      points = points + table(12, t)**2*(face_first(t + 1) - face_first(t))
      if (table(11, t) == surface_gauss) points = points + tool_first(t + 1) - tool_first(t)
    end do
    if (points /= npoint) return
    do t = 1, ntool
      if (tool_first(t + 1) < tool_first(t) .or. face_first(t + 1) < face_first(t)) return
      if (any(corner(:, face_first(t) + 1:face_first(t + 1)) >= &
              tool_first(t + 1) - tool_first(t))) return
      np_ = table(3, t)
      po = table(7, t)
      if (np_ < 1 .or. po < 0 .or. table(6, t) < 0 .or. table(8, t) < 0 .or. &
          table(9, t) < 0) return
      if (table(6, t) + table(2, t)*np_ > ncoef .or. po + np_ > ntri .or. &
          2*(po + np_) > ndeg .or. po + np_ > nframe .or. &
          table(8, t) + 2*np_ - 1 > ntree .or. po + t + np_ > nstart) return
      first = grid_start(po + t)
      last = grid_start(po + t + np_)
      if (first /= 1 .or. last < first .or. table(9, t) + last - 1 > ngrid) return
      if (table(11, t) < 0 .or. table(11, t) > 2) return
      if (table(11, t) == 0) then
        do p = tool_first(t) + 1, tool_first(t + 1)
          if (patch_first(p + 1) - patch_first(p) /= 1) return
          if (patch_node(patch_first(p + 1)) /= pair_node(p)) return
        end do
        cycle
      end if
      do f = face_first(t) + 1, face_first(t + 1)
        do q = 1, 4
          if (corner(q, f) < 0) cycle
          p = tool_first(t) + corner(q, f) + 1
          if (faces(q, f) /= pair_node(p)) return
          do qq = 1, 4
            found = .false.
            do e = patch_first(p) + 1, patch_first(p + 1)
              if (patch_node(e) == faces(qq, f)) found = .true.
            end do
            if (.not. found) return
          end do
        end do
      end do
    end do
    coupled = count(eqn(:, pair_node + 1) >= 0)
    ! dC/dx: 3 rows per pair over its patch's free dofs; a surface-to-surface or
    ! Gauss-point pair has no row for a held component (its law is lambda_k = 0).
    entries = 0
    do t = 1, ntool
      do p = tool_first(t) + 1, tool_first(t + 1)
        rows = 3
        if (table(11, t) /= 0) rows = count(eqn(:, pair_node(p) + 1) >= 0)
        entries = entries + rows*count(eqn(:, patch_node(patch_first(p) + 1: &
                                                         patch_first(p + 1)) + 1) >= 0)
      end do
    end do
    ok = k_slots >= 0 .and. &
         (nvalues == k_slots + coupled + entries + 9*npair .or. nvalues == 0)
  end function layout_ok

  !> Whether a row structure (ddpy.core.linalg.row_structure) fits: rows and sources in
  !> order from 0 to their counts, columns in 0..n-1, sources in 0..nvalues-1.
  pure logical function rows_ok(n, ncsr, nsrc, nvalues, row_start, col, sources, &
                                source_start) result(ok)
    integer(c_int), intent(in) :: n, ncsr, nsrc, nvalues, row_start(n + 1), col(ncsr), &
                                  sources(nsrc), source_start(ncsr + 1)
    ok = row_start(1) == 0 .and. row_start(n + 1) == ncsr .and. &
         all(row_start(2:) >= row_start(:n)) .and. source_start(1) == 0 .and. &
         source_start(ncsr + 1) == nsrc .and. all(source_start(2:) >= source_start(:ncsr)) &
         .and. all(col >= 0 .and. col < n) .and. all(sources >= 0 .and. sources < nvalues)
  end function rows_ok

  !> Contact of every (tool, slave) pair: see forming_contact.
  subroutine api_forming_contact(nnode, x, x_n, fixed, ntool, table, tol, ncoef, coef, &
                                 ndeg, degrees, ntri, triangle, ntree, tree_lower, &
                                 tree_upper, tree_child, nframe, frame, frame_lower, &
                                 frame_upper, nstart, grid_start, ngrid, grid_params, &
                                 grid_normals, grid_points, facing, face_first, nface, &
                                 faces, corner, npoint, face_weight, penalty, positions, &
                                 positions_n, reach, size, touching, resting, npair, tool_first, &
                                 pair_node, npatch, patch_first, patch_node, on, force, r, mu, &
                                 held, traction_n, pressure_n, eqn, nf, k_slots, nvalues, &
                                 residual, values, state, gap, normal, traction, pressure, &
                                 status, nhold, hold_tool, hold_axis, hold_target, &
                                 hold_first, nhold_src, hold_source, hold_coef) &
    bind(C, name="ddpy_forming_contact")
    integer(c_int), value, intent(in) :: nnode, ntool, ncoef, ndeg, ntri, ntree, nframe, &
                                         nstart, ngrid, nface, npoint, resting, npair, npatch, &
                                         nf, k_slots, nvalues, nhold, nhold_src
    integer(c_int), intent(in) :: hold_tool(nhold), hold_first(nhold + 1), &
                                  hold_source(nhold_src)
    real(c_double), intent(in) :: hold_axis(3, nhold), hold_target(nhold), hold_coef(nhold_src)
    real(c_double), value, intent(in) :: reach, size, touching
    real(c_double), intent(in) :: x(3, nnode), x_n(3, nnode), tol(ntool), coef(ncoef), &
                                  tree_lower(3*ntree), tree_upper(3*ntree), frame(9*nframe), &
                                  frame_lower(3*nframe), frame_upper(3*nframe), &
                                  grid_params(2*ngrid), grid_normals(3*ngrid), &
                                  grid_points(3*ngrid), facing(3, ntool), &
                                  positions(3, ntool), positions_n(3, ntool), &
                                  force(3, npair), r(npair), mu(npair), face_weight(npoint), &
                                  penalty(5, ntool), traction_n(3, npoint), &
                                  pressure_n(npoint)
    integer(c_int), intent(in) :: fixed(3, nnode), table(tool_fields, ntool), degrees(ndeg), &
                                  triangle(ntri), tree_child(ntree), grid_start(nstart), &
                                  face_first(ntool + 1), faces(4, nface), corner(4, nface), &
                                  tool_first(ntool + 1), pair_node(npair), on(npair), &
                                  patch_first(npair + 1), patch_node(npatch), &
                                  held(3, npair), eqn(3, nnode)
    real(c_double), intent(inout) :: residual(nf + 3*npair + nhold), values(nvalues)
    integer(c_int), intent(out) :: state(npair), status
    real(c_double), intent(out) :: gap(npair), normal(3, npair), traction(3, npoint), &
                                   pressure(npoint)
    integer, allocatable :: lock(:), found(:)
    real(wp), allocatable :: dc_dt(:, :, :), lambda(:, :), stiffness(:)
    logical, allocatable :: eliminated(:)
    integer :: entries, contact_values, t, p
    state = 0
    gap = 0.0_wp
    normal = 0.0_wp
    traction = 0.0_wp
    pressure = 0.0_wp
    status = 1
    entries = hold_entries(ntool, table, npair, tool_first, pair_node, nnode, eqn, nhold, &
                           hold_tool, hold_first, nhold_src)
    if (entries < 0) return
    contact_values = 0
    if (nvalues > 0) contact_values = nvalues - entries
    if (any(hold_source >= contact_values) .and. nvalues > 0) return
    if (.not. layout_ok(nnode, ntool, table, ncoef, ndeg, ntri, ntree, nframe, nstart, ngrid, &
                        grid_start, face_first, nface, faces, corner, npoint, npair, &
                        tool_first, pair_node, npatch, patch_first, patch_node, eqn, &
                        k_slots, contact_values)) return
    status = 0
    allocate(lock(npair + npoint), found(npair + npoint), dc_dt(3, 3, npair), &
             lambda(3, npair), eliminated(npair), stiffness(nhold))
    lock = 0  ! no pair held: a plain search
    call forming_contact(nnode, x, x_n, fixed, ntool, table, tol, coef, degrees, triangle, &
                         tree_lower, tree_upper, tree_child, frame, frame_lower, frame_upper, &
                         grid_start, grid_params, grid_normals, grid_points, facing, &
                         face_first, nface, faces, corner, npoint, face_weight, penalty, &
                         positions, positions_n, reach, size, touching, resting, npair, tool_first, &
                         pair_node, npatch, patch_first, patch_node, on, force, r, mu, held, &
                         traction_n, pressure_n, lock, eqn, nf, k_slots, contact_values, &
                         residual(1:nf + 3*npair), values, state, gap, normal, traction, &
                         pressure, found, dc_dt)
    if (nhold == 0 .or. nvalues == 0) return
    ! The tools' equations as the Newton loop has them: a Gauss-point pair's lambda is F(x)
    ! (its law's residual is lambda - F).
    lambda = force
    do t = 1, ntool
      do p = tool_first(t) + 1, tool_first(t + 1)
        eliminated(p) = table(11, t) == 2
        if (eliminated(p)) lambda(:, p) = force(:, p) - residual(nf + 3*p - 2:nf + 3*p)
      end do
    end do
    call hold_equations(nnode, ntool, npair, tool_first, pair_node, on, eqn, eliminated, &
                        lambda, dc_dt, nhold, hold_tool, hold_axis, hold_target, hold_first, &
                        nhold_src, hold_source, hold_coef, contact_values, &
                        residual(nf + 3*npair + 1:), values, stiffness)
  end subroutine api_forming_contact

  !> The Jacobian entries of the force-controlled tools (forming_increment: per tool its
  !> column, row and diagonal), or -1 where they do not fit: a tool out of range or given
  !> twice, the rows' entries not in order.
  integer function hold_entries(ntool, table, npair, tool_first, pair_node, nnode, eqn, &
                                nhold, hold_tool, hold_first, nhold_src) result(entries)
    integer(c_int), intent(in) :: ntool, npair, nnode, nhold, nhold_src
    integer(c_int), intent(in) :: table(tool_fields, ntool), tool_first(ntool + 1), &
                                  pair_node(npair), eqn(3, nnode), hold_tool(nhold), &
                                  hold_first(nhold + 1)
    integer :: k, p, t
    entries = -1
    if (nhold < 0 .or. any(hold_tool < 1) .or. any(hold_tool > ntool)) return
    if (hold_first(1) /= 0 .or. hold_first(nhold + 1) /= nhold_src) return
    if (any(hold_first(2:) < hold_first(:nhold))) return
    if (any(tool_first(2:) < tool_first(:ntool)) .or. tool_first(ntool + 1) /= npair) return
    if (any(pair_node < 0) .or. any(pair_node >= nnode)) return
    entries = 0
    do k = 1, nhold
      t = hold_tool(k)
      if (count(hold_tool == t) /= 1) then
        entries = -1
        return
      end if
      do p = tool_first(t) + 1, tool_first(t + 1)
        if (table(11, t) == 2) then
          entries = entries + count(eqn(:, pair_node(p) + 1) >= 0)
        else
          entries = entries + 3
        end if
      end do
      entries = entries + hold_first(k + 1) - hold_first(k) + 1
    end do
  end function hold_entries

  !> Newton iterations of one increment: see forming_increment. Connectivity arrives 0-based.
  subroutine api_forming_increment(nnode, x0, ne, conn, kind, props, u_ref, axes_old, &
                                   stress_old, ep_old, strain_old, nback, back_old, eqn, &
                                   offsets, fixed, nf, &
                                   k_slots, n_coupling, nvalues, nrow, row_start, ncsr, col, &
                                   nsrc, sources, source_start, ntool, table, tol, ncoef, &
                                   coef, ndeg, degrees, ntri, triangle, ntree, tree_lower, &
                                   tree_upper, tree_child, nframe, frame, frame_lower, &
                                   frame_upper, nstart, grid_start, ngrid, grid_params, &
                                   grid_normals, grid_points, facing, face_first, nface, &
                                   faces, corner, npoint, face_weight, penalty, positions, &
                                   positions_n, reach, size, touching, npair, tool_first, &
                                   pair_node, npatch, patch_first, patch_node, on, r, mu, held, &
                                   traction_n, pressure_n, u_n, force_n, external, &
                                   prescribed, guess, settings, isettings, factored, &
                                   reuse_next, u, force, fint, stress, ep, strain, axes, back, &
                                   state, gap, normal, traction, pressure, nhistory, niter, &
                                   history, counters, timings, outcome, info, detail, nhold, &
                                   hold_tool, hold_axis, hold_target, hold_first, nhold_src, &
                                   hold_source, hold_coef, hold_step, shift) &
    bind(C, name="ddpy_forming_increment")
    integer(c_int), value, intent(in) :: nnode, ne, kind, nf, k_slots, n_coupling, nvalues, &
                                         nrow, ncsr, nsrc, ntool, ncoef, ndeg, ntri, ntree, &
                                         nframe, nstart, ngrid, nface, npoint, npair, npatch, &
                                         nhistory, nback, nhold, nhold_src
    real(c_double), value, intent(in) :: reach, size, touching, hold_step
    integer(c_int), intent(in) :: hold_tool(nhold), hold_first(nhold + 1), &
                                  hold_source(nhold_src)
    real(c_double), intent(in) :: hold_axis(3, nhold), hold_target(nhold), hold_coef(nhold_src)
    real(c_double), intent(out) :: shift(nhold)
    integer(c_int), intent(in) :: conn(8, ne), eqn(3, nnode), offsets(ne + 1), &
                                  fixed(3, nnode), row_start(nrow + 1), col(ncsr), &
                                  sources(nsrc), source_start(ncsr + 1), &
                                  table(tool_fields, ntool), degrees(ndeg), triangle(ntri), &
                                  tree_child(ntree), grid_start(nstart), &
                                  face_first(ntool + 1), faces(4, nface), corner(4, nface), &
                                  tool_first(ntool + 1), pair_node(npair), on(npair), &
                                  patch_first(npair + 1), patch_node(npatch), &
                                  held(3, npair), isettings(newton_integer_settings)
    real(c_double), intent(in) :: x0(3, nnode), props(material_prop_count), &
                                  u_ref(3, nnode), axes_old(3, 3, 8, ne), &
                                  stress_old(6, 8, ne), ep_old(8, ne), strain_old(6, 8, ne), &
                                  back_old(6, 8, nback), &
                                  tol(ntool), coef(ncoef), tree_lower(3*ntree), &
                                  tree_upper(3*ntree), frame(9*nframe), &
                                  frame_lower(3*nframe), frame_upper(3*nframe), &
                                  grid_params(2*ngrid), grid_normals(3*ngrid), &
                                  grid_points(3*ngrid), facing(3, ntool), &
                                  face_weight(npoint), penalty(5, ntool), &
                                  traction_n(3, npoint), pressure_n(npoint), &
                                  positions(3, ntool), positions_n(3, ntool), r(npair), &
                                  mu(npair), u_n(3, nnode), force_n(3, npair), &
                                  external(3, nnode), prescribed(3, nnode), &
                                  guess(3, nnode), settings(newton_settings)
    integer(c_int), intent(inout) :: factored, reuse_next
    real(c_double), intent(out) :: u(3, nnode), force(3, npair), fint(3, nnode), &
                                   stress(6, 8, ne), ep(8, ne), &
                                   strain(6, 8, ne), axes(3, 3, 8, ne), back(6, 8, nback), &
                                   gap(npair), &
                                   normal(3, npair), traction(3, npoint), pressure(npoint), &
                                   history(4, nhistory), timings(4), detail(2)
    integer(c_int), intent(out) :: state(npair), niter, counters(5), outcome, info(4)
    integer :: entries
    history = 0.0_wp
    shift = 0.0_wp
    outcome = -1
    if (nhistory < isettings(1) + 1 .or. offsets(ne + 1) /= k_slots) return
    if (kind /= kind_hexahedron .and. kind /= kind_solid_shell) return
    if (any(conn < 0) .or. any(conn >= nnode) .or. nrow /= nf + 3*npair + nhold) return
    if (.not. rows_ok(nrow, ncsr, nsrc, nvalues, row_start, col, sources, source_start)) return
    ! The force-controlled tools: each a tool once, its row's sources in the contact
    ! blocks, and their entries (column, row, diagonal) the last of the values.
    entries = hold_entries(ntool, table, npair, tool_first, pair_node, nnode, eqn, nhold, &
                           hold_tool, hold_first, nhold_src)
    if (entries < 0) return
    if (any(hold_source >= nvalues - entries)) return
    if (.not. layout_ok(nnode, ntool, table, ncoef, ndeg, ntri, ntree, nframe, nstart, ngrid, &
                        grid_start, face_first, nface, faces, corner, npoint, npair, &
                        tool_first, pair_node, npatch, patch_first, patch_node, eqn, &
                        k_slots, nvalues - entries)) return
    call forming_increment(nnode, x0, ne, conn + 1, kind, props, u_ref, axes_old, stress_old, &
                           ep_old, strain_old, nback, back_old, eqn, offsets, fixed, nf, &
                           k_slots, n_coupling, &
                           nvalues, row_start, ncsr, col, sources, source_start, ntool, &
                           table, tol, coef, degrees, triangle, &
                           tree_lower, tree_upper, tree_child, frame, frame_lower, &
                           frame_upper, grid_start, grid_params, grid_normals, grid_points, &
                           facing, face_first, nface, faces, corner, npoint, face_weight, &
                           penalty, positions, positions_n, reach, size, touching, npair, tool_first, &
                           pair_node, npatch, patch_first, patch_node, on, r, mu, held, &
                           traction_n, pressure_n, u_n, force_n, external, prescribed, guess, &
                           settings, isettings, factored, reuse_next, u, force, fint, stress, &
                           ep, strain, axes, back, state, gap, normal, traction, pressure, &
                           niter, history, counters, timings, outcome, info, detail, nhold, &
                           hold_tool, hold_axis, hold_target, hold_first, nhold_src, &
                           hold_source, hold_coef, hold_step, shift)
  end subroutine api_forming_increment

  !> Newton iterations of one increment of a solid without tools (the static problem): see
  !> forming_increment, called with no tools and no pairs, whose empty arrays f2py cannot
  !> pass (it takes a zero length for one). Connectivity arrives 0-based.
  subroutine api_static_increment(nnode, x0, ne, conn, kind, props, u_ref, axes_old, &
                                  stress_old, ep_old, strain_old, nback, back_old, eqn, &
                                  offsets, fixed, nf, &
                                  k_slots, nvalues, ncsr, row_start, col, nsrc, sources, &
                                  source_start, size, u_n, external, prescribed, guess, &
                                  settings, isettings, factored, u, fint, stress, ep, strain, &
                                  axes, back, nhistory, niter, history, counters, timings, &
                                  outcome, info, detail) bind(C, name="ddpy_static_increment")
    integer(c_int), value, intent(in) :: nnode, ne, kind, nf, k_slots, nvalues, ncsr, nsrc, &
                                         nhistory, nback
    real(c_double), value, intent(in) :: size
    integer(c_int), intent(in) :: conn(8, ne), eqn(3, nnode), offsets(ne + 1), &
                                  fixed(3, nnode), row_start(nf + 1), col(ncsr), &
                                  sources(nsrc), source_start(ncsr + 1), &
                                  isettings(newton_integer_settings)
    real(c_double), intent(in) :: x0(3, nnode), props(material_prop_count), &
                                  u_ref(3, nnode), axes_old(3, 3, 8, ne), &
                                  stress_old(6, 8, ne), ep_old(8, ne), strain_old(6, 8, ne), &
                                  u_n(3, nnode), external(3, nnode), prescribed(3, nnode), &
                                  guess(3, nnode), settings(newton_settings), &
                                  back_old(6, 8, nback)
    integer(c_int), intent(inout) :: factored
    real(c_double), intent(out) :: u(3, nnode), fint(3, nnode), stress(6, 8, ne), ep(8, ne), &
                                   strain(6, 8, ne), axes(3, 3, 8, ne), back(6, 8, nback), &
                                   history(4, nhistory), &
                                   timings(4), detail(2)
    integer(c_int), intent(out) :: niter, counters(5), outcome, info(4)
    integer :: table(tool_fields, 0), ints(0), faces(4, 0), first(1), pairs(0), held(3, 0), &
               state(0), reuse_next
    real(wp) :: reals(0), tools(3, 0), forces(3, 0), force(3, 0), normal(3, 0), gap(0), &
                weights(0), penalty(5, 0), tractions(3, 0), traction(3, 0), pressures(0), &
                pressure(0), shift(0)
    history = 0.0_wp
    outcome = -1
    if (nhistory < isettings(1) + 1 .or. offsets(ne + 1) /= k_slots .or. nvalues /= k_slots) &
      return
    if (kind /= kind_hexahedron .and. kind /= kind_solid_shell) return
    if (any(conn < 0) .or. any(conn >= nnode)) return
    if (.not. rows_ok(nf, ncsr, nsrc, nvalues, row_start, col, sources, source_start)) return
    first = 0
    reuse_next = 0
    call forming_increment(nnode, x0, ne, conn + 1, kind, props, u_ref, axes_old, stress_old, &
                           ep_old, strain_old, nback, back_old, eqn, offsets, fixed, nf, &
                           k_slots, 0, nvalues, &
                           row_start, ncsr, col, sources, source_start, 0, table, reals, &
                           reals, ints, ints, reals, reals, ints, &
                           reals, reals, reals, ints, reals, reals, reals, tools, first, 0, &
                           faces, faces, 0, weights, penalty, tools, tools, 0.0_wp, size, &
                           0.0_wp, &
                           0, first, pairs, 0, first, pairs, pairs, reals, reals, held, &
                           tractions, pressures, u_n, forces, external, prescribed, &
                           guess, settings, isettings, factored, reuse_next, u, force, fint, &
                           stress, ep, strain, axes, back, state, gap, normal, traction, &
                           pressure, niter, &
                           history, &
                           counters, timings, outcome, info, detail, 0, pairs, tools, reals, &
                           first, 0, pairs, reals, 0.0_wp, shift)
  end subroutine api_static_increment

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

  !> GMRES of the Newton loop on W M^-1 J W^-1 (J the coordinate values summed into the rows
  !> row_start, col, sources, source_start, 0-based: ddpy.core.linalg.row_structure; M the
  !> factors held by the MUMPS instance handle): see gmres. converged is 1 or 0; status < 0
  !> a MUMPS solve failed, 1 an index out of range.
  subroutine api_krylov_solve(n, nvalues, values, ncsr, row_start, col, nsrc, sources, &
                              source_start, weight, handle, b, tol, m, z, k, converged, &
                              status) bind(C, name="ddpy_krylov_solve")
    integer(c_int), value, intent(in) :: n, nvalues, ncsr, nsrc, handle, m
    real(c_double), value, intent(in) :: tol
    integer(c_int), intent(in) :: row_start(n + 1), col(ncsr), sources(nsrc), &
                                  source_start(ncsr + 1)
    real(c_double), intent(in) :: values(nvalues), weight(n), b(n)
    real(c_double), intent(out) :: z(n)
    integer(c_int), intent(out) :: k, converged, status
    logical :: done
    z = 0.0_wp
    k = 0
    converged = 0
    status = 1
    if (.not. rows_ok(n, ncsr, nsrc, nvalues, row_start, col, sources, source_start) .or. &
        m < 1 .or. any(weight <= 0.0_wp)) return
    call gmres(n, nvalues, values, row_start, ncsr, col, sources, source_start, weight, &
               handle, b, tol, m, z, k, done, status)
    converged = merge(1, 0, done)
  end subroutine api_krylov_solve

end module ddpy_api_forming
