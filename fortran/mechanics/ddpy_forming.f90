!> The contact of a forming problem in one call: for every (tool, slave node) pair of every
!> active tool, the closest point on the tool, the Alart-Curnier residual with its
!> derivatives, and their place in the combined residual and Jacobian (docs/theory/contact.md).
!>
!> The unknowns are ordered as the core's layout numbers them (ddpy_jacobian_layout): the
!> free displacement dofs first (eqn), then 3 force components per pair. The Jacobian's
!> contact blocks are written into the layout's slots: the coupling entries (their values
!> set once by the caller), then dC/dx at the free dofs of each pair's node (pair-major,
!> row, column), then dC/dlambda (pair-major, row, column). A pair's dC/dx runs over the nodes of its
!> patch (patch_first, patch_node): its own node for node-to-surface contact, every node of
!> the blank faces around it for surface-to-surface and Gauss-point contact (row, patch
!> node, column).
!> The tools, the pairs and their law arrive packed in the derived types of
!> ddpy_forming_data, built once by the api layer.
module ddpy_forming
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_positive_inf
  use ddpy_kinds, only: wp
  use ddpy_surface, only: patch_evaluate
  use ddpy_global_search, only: contact_none, contact_inside, contact_edge, memory_rows
  use ddpy_search_surface, only: surface_contact_search
  use ddpy_contact, only: contact_residual, contact_law, normal_derivative, contact_inactive, &
                          gauss_traction
  use ddpy_blank, only: blank_dofs
  use ddpy_forming_data, only: tool_set, pair_set, pair_law, increment_limits, contact_node, &
                               contact_gauss, max_face_order, has_barrier, node_point
  implicit none
  private
  public :: forming_contact, rank_of_rows, gauss_legendre

  !> The corners of a blank face in its parameters (xi, eta).
  real(wp), parameter :: corner_xi(4) = [-1.0_wp, 1.0_wp, 1.0_wp, -1.0_wp], &
                         corner_eta(4) = [-1.0_wp, -1.0_wp, 1.0_wp, 1.0_wp]
  !> A singular value of the rigid-mode rows above this counts (numpy's matrix_rank tol).
  real(wp), parameter :: rank_tolerance = 1.0e-9_wp
  !> Pairs and Gauss points held on their patch (forming_contact's found) lie less than
  !> this many element sizes outside the tool: a held point far from the tool would carry
  !> the patch's plane continued far past its edges into the averaged gaps of its pairs.
  real(wp), parameter :: hold_band = 1.0e-2_wp
  !> A touching pair's force is lifted this far past p_aug = 0 (times r and the size).
  real(wp), parameter :: lift_fraction = 1.0e-9_wp

contains

  !> Contact of the pairs at positions x (3, nnode), from the converged x_n, with each
  !> tool at positions(:, t) (at positions_n(:, t) when converged), the pairs that take
  !> part (law%on) with their law, the search within limits%reach; writes the contact part
  !> of the residual (the law's rows, and the pairs' forces in the equilibrium rows, which
  !> the caller has filled with fint - external) and of the Jacobian values (none when
  !> nvalues is 0).
  !>
  !> touching > 0: the predictor of an increment's first iteration (see
  !> ddpy.model.forming): a pair the law leaves open within that gap takes the closed
  !> branch; unless limits%resting, those of a tool at rest only when the blank needs them
  !> (the supports, the pairs the law closes and the touching pairs of the moving tools
  !> leave a rigid motion free). A pair that found no patch (or whose tool is off) keeps
  !> C = lambda, state 0 and an infinite gap.
  !>
  !> A surface-to-surface tool (discretization contact_surface) projects the n x n Gauss
  !> points of its faces instead of its slaves: each slave's gap, normal and slip are the averages over
  !> the faces around it weighted by its shape function and face_weight (the Gauss weight
  !> times the face's area element in the undeformed blank), and its law's derivatives
  !> along x run over the nodes of those faces (docs/theory/contact.md).
  !>
  !> A Gauss-point tool (discretization contact_gauss) puts the penalty law of
  !> gauss_traction at those Gauss points (its normal and tangential penalty, N/mm^3;
  !> law%traction_n(:, i): each point's tangential traction at the last converged
  !> increment, traction: the new one, zero elsewhere; law%pressure_n(i): its pressure
  !> multiplier, pressure: its new pressure); F(x), each slave's share of the points'
  !> forces by the shape functions, is its lumped force (lumped), which the equilibrium
  !> rows take with its derivative dF/dx (the layout puts a Gauss-point pair's patch
  !> entries in its node's equilibrium rows). Without a barrier (barrier_depth < 0) each
  !> slave's law is C = lambda - F(x): its multiplier is eliminated, its law rows have
  !> dC/dlambda = I alone, and the Newton loop sets lambda = F(x) at each evaluation
  !> (forming_increment). With a barrier, lambda is the slave's own force besides F, the
  !> Alart-Curnier law of contact_residual for the slave at the depth barrier_depth in the
  !> tool (its gap measured from there, along the tool's normal at its closest point):
  !> the equilibrium rows take F(x) + lambda, the law rows depend on lambda and the slave
  !> alone (no fill), and the slave's point after the tool's Gauss points (its node point)
  !> carries lambda from increment to increment as its traction (docs/theory/contact.md,
  !> "The barrier").
  !>
  !> nmemory = npair + npoint: memory, memory_patch are the search's memory of each pair's
  !> node and each Gauss point (ddpy_global_search.contact_search, indexed as lock), kept
  !> by the caller over the evaluations of an increment; nmemory = 0: none.
  !>
  !> lock(p) > 0 holds node-to-surface pair p on that patch of its tool (ddpy_global_search:
  !> no search, the patch's plane continued past its edges), lock(npair + i) Gauss point i
  !> of a surface-to-surface or Gauss-point tool; found gives the patch each of them took
  !> where it lies less than hold_band element sizes outside the tool (0 elsewhere: none,
  !> farther, or not that kind of contact), the ones worth holding. dc_dt(:, :, p): the
  !> derivative of pair p's law (of C = lambda - F for a Gauss-point pair) along a
  !> translation of its tool, zero in a held component's row; barrier_dt(:, :, p): that
  !> of a barrier pair's own law (zero for the others).
  subroutine forming_contact(x, x_n, dofs, tools, pairs, law, positions, positions_n, limits, &
                             touching, force, lock, nmemory, memory, memory_patch, nvalues, &
                             residual, values, state, gap, normal, traction, pressure, found, &
                             dc_dt, lumped, barrier_dt)
    real(wp), intent(in) :: x(:, :), x_n(:, :)
    type(blank_dofs), intent(in) :: dofs
    type(tool_set), intent(in) :: tools
    type(pair_set), intent(in) :: pairs
    type(pair_law), intent(in) :: law
    real(wp), intent(in) :: positions(3, tools%ntool), positions_n(3, tools%ntool)
    type(increment_limits), intent(in) :: limits
    real(wp), intent(in) :: touching, force(3, pairs%npair)
    integer, intent(in) :: lock(pairs%npair + tools%npoint), nvalues, nmemory
    real(wp), intent(inout) :: memory(memory_rows, nmemory)
    integer, intent(inout) :: memory_patch(nmemory)
    real(wp), intent(inout) :: residual(dofs%nf + 3*pairs%npair), values(nvalues)
    integer, intent(out) :: state(pairs%npair), found(pairs%npair + tools%npoint)
    real(wp), intent(out) :: gap(pairs%npair), normal(3, pairs%npair), &
                             traction(3, tools%npoint), pressure(tools%npoint), &
                             dc_dt(3, 3, pairs%npair), lumped(3, pairs%npair), &
                             barrier_dt(3, 3, pairs%npair)
    real(wp), allocatable :: nodes(:, :), node_normals(:, :), params(:, :), points(:, :), &
                             tangents(:, :, :), distance(:), p_aug(:), c(:, :), &
                             dc_dlambda(:, :, :), dc_dx(:, :, :), slip(:, :), &
                             patch_gap(:, :), patch_normal(:, :, :), patch_weight(:), &
                             patch_dc(:, :, :), gauss_force(:, :)
    ! A barrier pair's slave: where it found the tool (barred), its gap from the barrier's
    ! depth, the tool's normal and its derivative there, the slave's slip.
    real(wp), allocatable :: bar_gap(:), bar_normal(:, :), bar_dndx(:, :, :), bar_slip(:, :)
    logical, allocatable :: barred(:), barrier_pair(:)
    integer, allocatable :: patch(:), status(:), iterations(:), ncandidates(:)
    logical, allocatable :: searched(:), shut(:), surface(:)
    integer :: t, p, a, b, k, i, j, e, slot, nnode, ntool, npair, npatch, npoint, nf, k_slots, &
               bar_state
    real(wp) :: d2(3, 3), point(3), d1(3, 2), lam(3), v(3), dndx(3, 3), lift, element_size

    nnode = size(x, 2)
    ntool = tools%ntool
    npair = pairs%npair
    npatch = pairs%npatch
    npoint = tools%npoint
    nf = dofs%nf
    k_slots = dofs%k_slots
    element_size = limits%element_size
    allocate(searched(ntool), shut(npair), p_aug(npair), tangents(3, 2, npair), &
             params(2, npair), patch(npair), status(npair), surface(npair))
    allocate(c(3, npair), dc_dlambda(3, 3, npair), dc_dx(3, 3, npair))
    ! Surface-to-surface pairs: the weighted slip, and per patch entry the derivatives of
    ! the weighted gap and normal, the weight of the node in the slip, and dC/dx.
    allocate(slip(3, npair), patch_gap(3, npatch), patch_normal(3, 3, npatch), &
             patch_weight(npatch), patch_dc(3, 3, npatch))
    do t = 1, ntool
      surface(pairs%tool_first(t) + 1:pairs%tool_first(t + 1)) = &
        tools%tool(t)%discretization /= contact_node
    end do
    allocate(gauss_force(3, npair), bar_gap(npair), bar_normal(3, npair), &
             bar_dndx(3, 3, npair), bar_slip(3, npair), barred(npair), barrier_pair(npair))
    gauss_force = 0.0_wp
    barred = .false.
    do t = 1, ntool
      barrier_pair(pairs%tool_first(t) + 1:pairs%tool_first(t + 1)) = has_barrier(tools%tool(t))
    end do
    traction = 0.0_wp
    pressure = 0.0_wp
    patch_dc = 0.0_wp
    gap = ieee_value(1.0_wp, ieee_positive_inf)
    normal = 0.0_wp
    state = 0
    status = contact_none
    patch = 0
    found = 0
    shut = .false.
    p_aug = 0.0_wp
    ! Search each tool that has an active pair.
    do t = 1, ntool
      a = pairs%tool_first(t) + 1
      b = pairs%tool_first(t + 1)
      searched(t) = b >= a .and. any(law%on(a:b) /= 0)
      if (.not. searched(t)) cycle
      if (tools%tool(t)%discretization == contact_gauss) then
        call gauss_search(t)
        cycle
      end if
      if (tools%tool(t)%discretization /= contact_node) then
        call surface_search(t)
        cycle
      end if
      k = b - a + 1
      allocate(nodes(3, k), node_normals(3, k), points(3, k), distance(k), iterations(k), &
               ncandidates(k))
      do i = 1, k
        nodes(:, i) = x(:, pairs%node(a + i - 1) + 1)
      end do
      node_normals = 0.0_wp
      if (tools%tool(t)%faced) call facing_normals(t, k, node_normals)
      call search_tool(t, k, a - 1, nodes, node_normals, patch(a:b), params(:, a:b), &
                       points, normal(:, a:b), tangents(:, :, a:b), distance, status(a:b), &
                       iterations, ncandidates)
      found(a:b) = merge(patch(a:b), 0, distance < hold_band*element_size)
      do i = 1, k
        if (status(a + i - 1) /= contact_none) gap(a + i - 1) = distance(i)
      end do
      deallocate(nodes, node_normals, points, distance, iterations, ncandidates)
    end do
    if (touching > 0.0_wp) call touching_pairs()
    ! The law at every pair that found a patch; the others keep C = lambda.
    c = force
    dc_dlambda = 0.0_wp
    do i = 1, 3
      dc_dlambda(i, i, :) = 1.0_wp
    end do
    dc_dx = 0.0_wp
    do t = 1, ntool
      if (.not. searched(t)) cycle
      if (tools%tool(t)%discretization == contact_gauss) then
        if (.not. has_barrier(tools%tool(t))) then
          ! C = lambda - F(x): the pair's force is the lumped force of the Gauss points.
          do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)
            if (status(p) /= contact_none) c(:, p) = force(:, p) - gauss_force(:, p)
          end do
          cycle
        end if
        ! The barrier: the slave's own law at the barrier's depth; its lambda is carried
        ! as its node point's traction, and its pressure over its share of the area is
        ! the point's (a slave that found no patch keeps C = lambda).
        do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)
          i = node_point(tools, pairs, t, p)
          traction(:, i) = force(:, p)
          if (.not. barred(p)) cycle
          call contact_residual(force(:, p), bar_normal(:, p), bar_gap(p), &
                                bar_dndx(:, :, p), bar_slip(:, p), law%mu(p), law%r(p), &
                                c(:, p), dc_dlambda(:, :, p), dc_dx(:, :, p), bar_state)
          state(p) = max(state(p), bar_state)
          if (tools%face_weight(i) > 0.0_wp) &
            pressure(i) = max(dot_product(force(:, p), bar_normal(:, p)), 0.0_wp)/ &
                          tools%face_weight(i)
        end do
        cycle
      end if
      if (tools%tool(t)%discretization /= contact_node) then
        call surface_law(t)
        cycle
      end if
      !$omp parallel do schedule(static) private(point, d1, d2, lam, v, dndx, lift) &
      !$omp   if(pairs%tool_first(t + 1) - pairs%tool_first(t) > 256)
      do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)
        if (status(p) == contact_none) cycle
        call patch_evaluate(tools%tool(t)%surface%kind, tools%tool(t)%surface%stride, &
                            tools%tool(t)%surface%coef(:, patch(p)), &
                            tools%tool(t)%surface%degrees(:, patch(p)), params(1, p), &
                            params(2, p), point, d1, d2)
        v = (x(:, pairs%node(p) + 1) - x_n(:, pairs%node(p) + 1)) - &
            (positions(:, t) - positions_n(:, t))
        lam = force(:, p)
        if (shut(p)) then
          ! A normal force that lifts p_aug just above zero: the law then gives its
          ! closed branch (stick, C = r g n + r s, when nothing slides yet).
          lift = -p_aug(p) + lift_fraction*law%r(p)*element_size
          lam = lam + lift*normal(:, p)
        end if
        dndx = normal_derivative(tangents(:, :, p), d2, normal(:, p), gap(p))
        call contact_residual(lam, normal(:, p), gap(p), dndx, v, law%mu(p), law%r(p), c(:, p), &
                              dc_dlambda(:, :, p), dc_dx(:, :, p), state(p))
      end do
      !$omp end parallel do
    end do
    ! Components held by a support: lambda_k = 0.
    do p = 1, npair
      do i = 1, 3
        if (pairs%held(i, p) == 0) cycle
        c(i, p) = force(i, p)
        dc_dlambda(i, :, p) = 0.0_wp
        dc_dlambda(i, i, p) = 1.0_wp
        dc_dx(i, :, p) = 0.0_wp
      end do
    end do
    ! dC/dt of each pair along a translation t of its tool (for a Gauss-point pair, the
    ! derivative of C = lambda - F): the tool enters every gap and slip as x - t, so it is
    ! minus the sum of dC/dx over the pair's patch (a force-controlled tool's column,
    ! forming_increment; docs/theory/contact.md, "Force-controlled tools").
    barrier_dt = 0.0_wp
    do p = 1, npair
      if (surface(p)) then
        dc_dt(:, :, p) = -sum(patch_dc(:, :, pairs%patch_first(p) + 1: &
                                          pairs%patch_first(p + 1)), dim=3)
        if (barrier_pair(p)) barrier_dt(:, :, p) = -dc_dx(:, :, p)
      else
        dc_dt(:, :, p) = -dc_dx(:, :, p)
      end if
      do i = 1, 3
        if (pairs%held(i, p) /= 0) dc_dt(i, :, p) = 0.0_wp
      end do
    end do
    lumped = gauss_force
    ! Equilibrium rows: minus the forces of the tools on their slave nodes, in pair order;
    ! a Gauss-point pair's is the points' force F(x) itself (its multiplier is eliminated:
    ! its dF/dx goes into the equilibrium rows, see forming_increment).
    do t = 1, ntool
      do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)
        do i = 1, 3
          j = dofs%eqn(i, pairs%node(p) + 1)
          if (j < 0) cycle
          if (tools%tool(t)%discretization == contact_gauss) then
            residual(j + 1) = residual(j + 1) - gauss_force(i, p)
            if (barrier_pair(p)) residual(j + 1) = residual(j + 1) - force(i, p)
          else
            residual(j + 1) = residual(j + 1) - force(i, p)
          end if
        end do
      end do
    end do
    residual(nf + 1:) = reshape(c, [3*npair])
    if (nvalues == 0) return  ! a look at the gaps: no Jacobian wanted
    ! Jacobian: dC/dx at the free dofs of each pair's node, then dC/dlambda.
    slot = k_slots + count(dofs%eqn(:, pairs%node + 1) >= 0)
    do p = 1, npair
      if (surface(p)) then
        do i = 1, 3
          ! A held component's row is lambda_k = 0 (above): no patch entries in the
          ! structure (ddpy_jacobian_layout), which would join the patch's nodes.
          if (pairs%held(i, p) /= 0) cycle
          do e = pairs%patch_first(p) + 1, pairs%patch_first(p + 1)
            do j = 1, 3
              if (dofs%eqn(j, pairs%patch_node(e) + 1) < 0) cycle
              slot = slot + 1
              values(slot) = patch_dc(i, j, e)
            end do
          end do
        end do
        if (.not. barrier_pair(p)) cycle
      end if
      do i = 1, 3
        do j = 1, 3
          if (dofs%eqn(j, pairs%node(p) + 1) < 0) cycle
          slot = slot + 1
          values(slot) = dc_dx(i, j, p)
        end do
      end do
    end do
    do p = 1, npair
      do i = 1, 3
        do j = 1, 3
          slot = slot + 1
          values(slot) = dc_dlambda(i, j, p)
        end do
      end do
    end do

  contains

    !> The Gauss points of tool t's contact faces, npf = n x n per face in face order (gx;
    !> xi runs fastest), each with its face's unit normal from the diagonals (gn), and the
    !> shape functions of the corners (rows) at the points of a face (columns) (basis):
    !> what surface-to-surface and Gauss-point contact search and weigh.
    subroutine face_points(t, npf, basis, gx, gn)
      integer, intent(in) :: t, npf
      real(wp), intent(out) :: basis(4, npf), gx(:, :), gn(:, :)
      real(wp) :: area(3), e1(3), e2(3), xi(max_face_order)
      integer :: f, first, g, q, i, n
      n = tools%tool(t)%order
      call gauss_legendre(n, xi(:n))
      do g = 1, npf
        do q = 1, 4
          basis(q, g) = 0.25_wp*(1.0_wp + corner_xi(q)*xi(mod(g - 1, n) + 1))* &
                        (1.0_wp + corner_eta(q)*xi((g - 1)/n + 1))
        end do
      end do
      first = tools%face_first(t)
      do f = 1, tools%face_first(t + 1) - first
        e1 = x(:, tools%faces(3, first + f) + 1) - x(:, tools%faces(1, first + f) + 1)
        e2 = x(:, tools%faces(4, first + f) + 1) - x(:, tools%faces(2, first + f) + 1)
        area = [e1(2)*e2(3) - e1(3)*e2(2), e1(3)*e2(1) - e1(1)*e2(3), &
                e1(1)*e2(2) - e1(2)*e2(1)]
        if (norm2(area) > 0.0_wp) area = area/norm2(area)
        do g = 1, npf
          i = npf*(f - 1) + g
          gx(:, i) = 0.0_wp
          do q = 1, 4
            gx(:, i) = gx(:, i) + basis(q, g)*x(:, tools%faces(q, first + f) + 1)
          end do
          gn(:, i) = area
        end do
      end do
    end subroutine face_points

    !> The weighted gaps, normals and slips of the pairs of surface-to-surface tool t, with
    !> their derivatives along every node of their patches: the Gauss points of the tool's
    !> faces projected on it (the facing filter from each face's normal at x), and their
    !> gaps, normals and slips averaged around each slave with the weights N_a w J. A
    !> held component of a slave (a symmetry plane through it) is left out of its normal
    !> and slip, as the mirror image of its faces would cancel it. A pair none of whose
    !> points finds the tool has no partner (status none).
    subroutine surface_search(t)
      integer, intent(in) :: t
      real(wp), allocatable :: gx(:, :), gn(:, :), gparams(:, :), gpoints(:, :), &
                               gnormal(:, :), gtangents(:, :, :), gdistance(:), gdn(:, :, :), &
                               wsum(:), gsum(:), msum(:, :)
      integer, allocatable :: gpatch(:), gstatus(:), gits(:), gcand(:)
      real(wp) :: basis(4, tools%tool(t)%order**2), vg(3), w, wn, len_m, keep(3), &
                  m(3), eye(3, 3), proj(3, 3), gpt(3), gd1(3, 2), gd2(3, 3)
      integer :: f, first, nfc, kg, g, q, qq, s, p, e, i, lo, hi, npf, ip
      first = tools%face_first(t)
      nfc = tools%face_first(t + 1) - first
      npf = tools%tool(t)%order**2
      kg = npf*nfc
      do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)
        patch_gap(:, pairs%patch_first(p) + 1:pairs%patch_first(p + 1)) = 0.0_wp
        patch_normal(:, :, pairs%patch_first(p) + 1:pairs%patch_first(p + 1)) = 0.0_wp
        patch_weight(pairs%patch_first(p) + 1:pairs%patch_first(p + 1)) = 0.0_wp
        slip(:, p) = 0.0_wp
      end do
      if (kg == 0) return
      allocate(gx(3, kg), gn(3, kg), gparams(2, kg), gpoints(3, kg), gnormal(3, kg), &
               gtangents(3, 2, kg), gdistance(kg), gdn(3, 3, kg), gpatch(kg), gstatus(kg), &
               gits(kg), gcand(kg))
      call face_points(t, npf, basis, gx, gn)
      call search_points(t, kg, gx, gn, gpatch, gparams, gpoints, gnormal, gtangents, &
                         gdistance, gstatus, gits, gcand)
      ! The derivative of the tool's normal along each point (its curvature).
      gdn = 0.0_wp
      !$omp parallel do schedule(static) private(gpt, gd1, gd2) if(kg > 256)
      do i = 1, kg
        if (gstatus(i) == contact_none) cycle
        call patch_evaluate(tools%tool(t)%surface%kind, tools%tool(t)%surface%stride, &
                            tools%tool(t)%surface%coef(:, gpatch(i)), &
                            tools%tool(t)%surface%degrees(:, gpatch(i)), gparams(1, i), &
                            gparams(2, i), gpt, gd1, gd2)
        gdn(:, :, i) = normal_derivative(gtangents(:, :, i), gd2, gnormal(:, i), gdistance(i))
      end do
      !$omp end parallel do
      ! The sums over the points around each slave.
      lo = pairs%tool_first(t) + 1
      hi = pairs%tool_first(t + 1)
      allocate(wsum(lo:hi), gsum(lo:hi), msum(3, lo:hi))
      wsum = 0.0_wp
      gsum = 0.0_wp
      msum = 0.0_wp
      do f = 1, nfc
        do g = 1, npf
          i = npf*(f - 1) + g
          ip = tools%tool(t)%first_point + i
          if (gstatus(i) == contact_none) cycle
          vg = -(positions(:, t) - positions_n(:, t))
          do q = 1, 4
            s = tools%faces(q, first + f) + 1
            vg = vg + basis(q, g)*(x(:, s) - x_n(:, s))
          end do
          do q = 1, 4
            s = tools%corner(q, first + f)
            if (s < 0) cycle
            p = pairs%tool_first(t) + s + 1
            w = basis(q, g)*tools%face_weight(ip)
            wsum(p) = wsum(p) + w
            gsum(p) = gsum(p) + w*gdistance(i)
            msum(:, p) = msum(:, p) + w*gnormal(:, i)
            slip(:, p) = slip(:, p) + w*vg
            do qq = 1, 4
              e = patch_entry(p, tools%faces(qq, first + f))
              if (e == 0) cycle
              wn = w*basis(qq, g)
              patch_gap(:, e) = patch_gap(:, e) + wn*gnormal(:, i)
              patch_normal(:, :, e) = patch_normal(:, :, e) + wn*gdn(:, :, i)
              patch_weight(e) = patch_weight(e) + wn
            end do
          end do
        end do
      end do
      eye = 0.0_wp
      do i = 1, 3
        eye(i, i) = 1.0_wp
      end do
      do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)
        if (.not. wsum(p) > 0.0_wp) cycle
        keep = merge(0.0_wp, 1.0_wp, pairs%held(:, p) /= 0)
        m = keep*msum(:, p)/wsum(p)
        len_m = norm2(m)
        if (.not. len_m > 0.0_wp) cycle
        status(p) = contact_inside
        gap(p) = gsum(p)/wsum(p)
        normal(:, p) = m/len_m
        slip(:, p) = keep*slip(:, p)/wsum(p)
        ! d(m / |m|) = (I - n n) dm / |m|.
        proj = (eye - spread(normal(:, p), 2, 3)*spread(normal(:, p), 1, 3))/len_m
        do e = pairs%patch_first(p) + 1, pairs%patch_first(p + 1)
          patch_gap(:, e) = patch_gap(:, e)/wsum(p)
          do i = 1, 3
            patch_normal(i, :, e) = keep(i)*patch_normal(i, :, e)/wsum(p)
          end do
          patch_normal(:, :, e) = matmul(proj, patch_normal(:, :, e))
          patch_weight(e) = patch_weight(e)/wsum(p)
        end do
      end do
    end subroutine surface_search

    !> Gauss-point contact of tool t (discretization contact_gauss): the n x n Gauss
    !> points of its faces projected on it as in surface_search, the penalty law of each
    !> (gauss_traction, its tangential traction at the last converged increment from
    !> law%traction_n, the new one into traction), and the force of the points on each slave
    !> a, F_a = sum N_a(xi_g) A_g t_g (A_g = tools%face_weight, the undeformed area), into
    !> gauss_force, with -dF_a/dx_b into patch_dc (the pair's law is C = lambda - F). The
    !> pair's gap and normal (for the increment control) are the averages of its points'
    !> weighted by N_a A_g; its state the highest of its points' (slip over stick over open).
    subroutine gauss_search(t)
      integer, intent(in) :: t
      real(wp), allocatable :: gx(:, :), gn(:, :), gparams(:, :), gpoints(:, :), &
                               gnormal(:, :), gtangents(:, :, :), gdistance(:), &
                               wsum(:), gsum(:), msum(:, :)
      integer, allocatable :: gpatch(:), gstatus(:), gits(:), gcand(:)
      real(wp), allocatable :: node_depth(:), node_normal(:, :), node_uv(:, :), &
                               node_tangents(:, :, :)
      integer, allocatable :: node_patch(:)
      logical, allocatable :: node_found(:), node_edge(:)
      real(wp) :: basis(4, tools%tool(t)%order**2), vg(3), w, gpt(3), gd1(3, 2), &
                  gd2(3, 3), dndx(3, 3), tr(3), tangential(3), dtr(3, 3), mu_t, len_m, along(3)
      integer :: c
      integer :: f, first, nfc, kg, g, q, qq, s, p, e, i, lo, hi, gstate, npf, ip
      logical :: with_barrier
      first = tools%face_first(t)
      nfc = tools%face_first(t + 1) - first
      npf = tools%tool(t)%order**2
      kg = npf*nfc
      lo = pairs%tool_first(t) + 1
      hi = pairs%tool_first(t + 1)
      do p = lo, hi
        patch_dc(:, :, pairs%patch_first(p) + 1:pairs%patch_first(p + 1)) = 0.0_wp
      end do
      if (kg == 0 .or. hi < lo) return
      mu_t = law%mu(lo)
      allocate(gx(3, kg), gn(3, kg), gparams(2, kg), gpoints(3, kg), gnormal(3, kg), &
               gtangents(3, 2, kg), gdistance(kg), gpatch(kg), gstatus(kg), gits(kg), &
               gcand(kg))
      call face_points(t, npf, basis, gx, gn)
      call search_points(t, kg, gx, gn, gpatch, gparams, gpoints, gnormal, gtangents, &
                         gdistance, gstatus, gits, gcand)
      with_barrier = has_barrier(tools%tool(t))
      if (with_barrier) call node_depths(t, lo, hi, npair + tools%tool(t)%first_point + kg, node_depth, &
                                   node_normal, node_found, node_patch, node_uv, &
                                   node_tangents, node_edge)
      allocate(wsum(lo:hi), gsum(lo:hi), msum(3, lo:hi))
      wsum = 0.0_wp
      gsum = 0.0_wp
      msum = 0.0_wp
      do f = 1, nfc
        do g = 1, npf
          i = npf*(f - 1) + g
          ip = tools%tool(t)%first_point + i
          if (gstatus(i) == contact_none) cycle
          call patch_evaluate(tools%tool(t)%surface%kind, tools%tool(t)%surface%stride, &
                              tools%tool(t)%surface%coef(:, gpatch(i)), &
                              tools%tool(t)%surface%degrees(:, gpatch(i)), gparams(1, i), &
                              gparams(2, i), gpt, gd1, gd2)
          dndx = normal_derivative(gtangents(:, :, i), gd2, gnormal(:, i), gdistance(i))
          vg = -(positions(:, t) - positions_n(:, t))
          do q = 1, 4
            s = tools%faces(q, first + f) + 1
            vg = vg + basis(q, g)*(x(:, s) - x_n(:, s))
          end do
          call gauss_traction(law%traction_n(:, ip), law%pressure_n(ip), gnormal(:, i), &
                              gdistance(i), dndx, vg, mu_t, tools%tool(t)%normal_penalty, &
                              tools%tool(t)%tangential_penalty, tr, tangential, &
                              pressure(ip), dtr, gstate)
          traction(:, ip) = tangential
          do q = 1, 4
            s = tools%corner(q, first + f)
            if (s < 0) cycle
            p = lo + s
            w = basis(q, g)*tools%face_weight(ip)
            wsum(p) = wsum(p) + w
            gsum(p) = gsum(p) + w*gdistance(i)
            msum(:, p) = msum(:, p) + w*gnormal(:, i)
            status(p) = contact_inside
            state(p) = max(state(p), gstate)
            if (gstate == contact_inactive) cycle
            gauss_force(:, p) = gauss_force(:, p) + w*tr
            do qq = 1, 4
              e = patch_entry(p, tools%faces(qq, first + f))
              if (e == 0) cycle
              patch_dc(:, :, e) = patch_dc(:, :, e) - w*basis(qq, g)*dtr
            end do
          end do
        end do
      end do
      ! The barrier: each slave that finds the tool, its gap from the barrier's depth
      ! along the tool's normal at its closest point, the normal's derivative there and
      ! the slave's slip, for its own law (forming_contact).
      if (with_barrier) then
        do i = 1, hi - lo + 1
          if (.not. node_found(i)) cycle
          p = lo + i - 1
          s = pairs%node(p) + 1
          call patch_evaluate(tools%tool(t)%surface%kind, tools%tool(t)%surface%stride, &
                              tools%tool(t)%surface%coef(:, node_patch(i)), &
                              tools%tool(t)%surface%degrees(:, node_patch(i)), &
                              node_uv(1, i), node_uv(2, i), gpt, gd1, gd2)
          if (node_edge(i)) then
            ! The normal is the direction from the edge point to the slave, g its signed
            ! length: dn/dx = (I - n n^T - a a^T) / g, a along the edge (a patch's normal
            ! is normal to its edges, and so is n).
            along = cross3(cross3(node_tangents(:, 1, i), node_tangents(:, 2, i)), &
                           node_normal(:, i))
            if (norm2(along) > 0.0_wp) along = along/norm2(along)
            do c = 1, 3
              dndx(:, c) = -node_normal(:, i)*node_normal(c, i) - along*along(c)
              dndx(c, c) = dndx(c, c) + 1.0_wp
            end do
            dndx = dndx/merge(-node_depth(i), huge(1.0_wp), node_depth(i) /= 0.0_wp)
          else
            dndx = normal_derivative(node_tangents(:, :, i), gd2, node_normal(:, i), &
                                     -node_depth(i))
          end if
          barred(p) = .true.
          bar_gap(p) = tools%tool(t)%barrier_depth - node_depth(i)
          bar_normal(:, p) = node_normal(:, i)
          bar_dndx(:, :, p) = dndx
          bar_slip(:, p) = (x(:, s) - x_n(:, s)) - (positions(:, t) - positions_n(:, t))
        end do
      end if
      do p = lo, hi
        if (.not. wsum(p) > 0.0_wp) cycle
        gap(p) = gsum(p)/wsum(p)
        len_m = norm2(msum(:, p))
        if (len_m > 0.0_wp) normal(:, p) = msum(:, p)/len_m
      end do

    end subroutine gauss_search

    !> The depth (minus the signed distance) of each slave lo..hi of tool t in it, the
    !> tool's normal there, its patch, parameters and tangents, by the search of
    !> node-to-surface contact, held where lock(first + 1..) says so and the patches taken
    !> into found as for the Gauss points; inside where the search finds a nearest point
    !> (inside a patch or on an edge: edge).
    subroutine node_depths(t, lo, hi, first, depth, normals, inside, on_patch, uv, tangent, &
                           edge)
      integer, intent(in) :: t, lo, hi, first
      real(wp), allocatable, intent(out) :: depth(:), normals(:, :), uv(:, :), &
                                            tangent(:, :, :)
      logical, allocatable, intent(out) :: inside(:), edge(:)
      integer, allocatable, intent(out) :: on_patch(:)
      real(wp), allocatable :: at(:, :), facing_at(:, :), on_tool(:, :)
      integer, allocatable :: how(:), its(:), candidates(:)
      integer :: k, i
      real(wp) :: dist
      k = hi - lo + 1
      allocate(depth(k), normals(3, k), inside(k), edge(k), at(3, k), facing_at(3, k), &
               uv(2, k), on_tool(3, k), tangent(3, 2, k), on_patch(k), how(k), its(k), &
               candidates(k))
      do i = 1, k
        at(:, i) = x(:, pairs%node(lo + i - 1) + 1)
      end do
      facing_at = 0.0_wp
      if (tools%tool(t)%faced) call facing_normals(t, k, facing_at)
      call search_tool(t, k, first, at, facing_at, on_patch, uv, on_tool, &
                       normals, tangent, depth, how, its, candidates)
      found(first + 1:first + k) = merge(on_patch, 0, depth < hold_band*element_size)
      ! A slave whose nearest point is on a patch's edge (as between two Nagata patches
      ! whose normals differ a little along their common edge) is measured there too, as
      ! the Gauss points are: left out, a node crossing the thin wedge of such points loses
      ! and regains its whole barrier force. The square cup's punch met one node at once
      ! 0.36 mm deep (2.6e5 N) at 19.3 mm of travel, where the run then failed; measured
      ! at edges too, it runs on (docs/theory/contact.md, "The barrier").
      inside = how /= contact_none
      edge = how == contact_edge
      ! There its normal is the direction from the edge point to the slave, which turns
      ! continuously from one patch's normal to the other's across the wedge (the
      ! patch's own normal at the edge point jumped there: the square cup's residual
      ! then chattered near 2e-3 of its force scale at 27.8 mm, and the run failed).
      do i = 1, k
        if (how(i) /= contact_edge) cycle
        dist = norm2(at(:, i) - on_tool(:, i))
        if (dist > 0.0_wp) normals(:, i) = sign(1.0_wp, depth(i))*(at(:, i) - on_tool(:, i))/dist
      end do
      depth = -depth
    end subroutine node_depths

    !> Entry of node (0-based) in the patch of pair p; 0 when it is not there.
    pure integer function patch_entry(p, node) result(entry)
      integer, intent(in) :: p, node
      integer :: e
      entry = 0
      do e = pairs%patch_first(p) + 1, pairs%patch_first(p + 1)
        if (pairs%patch_node(e) == node) then
          entry = e
          return
        end if
      end do
    end function patch_entry

    !> The law at every pair of surface-to-surface tool t that has a partner, its
    !> derivatives along the weighted gap, normal and slip chained to the nodes of its
    !> patch: dC/dx_b = dC/dg dg/dx_b + dC/dn dn/dx_b + dC/dv w_b (held components of the
    !> slip left out, as in surface_search).
    subroutine surface_law(t)
      integer, intent(in) :: t
      real(wp) :: lam(3), lift, dc_dg(3), dc_dn(3, 3), dc_dv(3, 3), keep(3)
      integer :: p, e, j
      !$omp parallel do schedule(static) private(lam, lift, dc_dg, dc_dn, dc_dv, keep, e, j) &
      !$omp   if(pairs%tool_first(t + 1) - pairs%tool_first(t) > 256)
      do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)
        if (status(p) == contact_none) cycle
        lam = force(:, p)
        if (shut(p)) then
          lift = -p_aug(p) + lift_fraction*law%r(p)*element_size
          lam = lam + lift*normal(:, p)
        end if
        call contact_law(lam, normal(:, p), gap(p), slip(:, p), law%mu(p), law%r(p), c(:, p), &
                         dc_dlambda(:, :, p), dc_dg, dc_dn, dc_dv, state(p))
        keep = merge(0.0_wp, 1.0_wp, pairs%held(:, p) /= 0)
        do e = pairs%patch_first(p) + 1, pairs%patch_first(p + 1)
          patch_dc(:, :, e) = matmul(dc_dn, patch_normal(:, :, e))
          do j = 1, 3
            patch_dc(:, j, e) = patch_dc(:, j, e) + dc_dg*patch_gap(j, e) + &
                                dc_dv(:, j)*keep(j)*patch_weight(e)
          end do
        end do
      end do
      !$omp end parallel do
    end subroutine surface_law

    !> search_tool for the kg Gauss points of tool t's faces (at gx, face normals gn), each
    !> held on its patch where lock says so, the patches taken into found.
    subroutine search_points(t, kg, gx, gn, gpatch, gparams, gpoints, gnormal, gtangents, &
                             gdistance, gstatus, gits, gcand)
      integer, intent(in) :: t, kg
      real(wp), intent(in) :: gx(3, kg), gn(3, kg)
      integer, intent(out) :: gpatch(kg), gstatus(kg), gits(kg), gcand(kg)
      real(wp), intent(out) :: gparams(2, kg), gpoints(3, kg), gnormal(3, kg), &
                               gtangents(3, 2, kg), gdistance(kg)
      integer :: first_point
      first_point = npair + tools%tool(t)%first_point
      call search_tool(t, kg, first_point, gx, gn, gpatch, &
                       gparams, gpoints, gnormal, gtangents, gdistance, gstatus, gits, gcand)
      found(first_point + 1:first_point + kg) = merge(gpatch, 0, gdistance < hold_band*element_size)
    end subroutine search_points

    !> Global and local search of the k slaves of tool t, first + 1 .. first + k in lock
    !> and the memory.
    subroutine search_tool(t, k, first, nodes, node_normals, patch, params, points, normals, &
                           tangents, distance, status, iterations, ncandidates)
      integer, intent(in) :: t, k, first
      real(wp), intent(in) :: nodes(3, k), node_normals(3, k)
      integer, intent(out) :: patch(k), status(k), iterations(k), ncandidates(k)
      real(wp), intent(out) :: params(2, k), points(3, k), normals(3, k), tangents(3, 2, k), &
                               distance(k)
      integer :: m
      m = merge(k, 0, nmemory > 0)  ! without a memory its sections are empty
      call surface_contact_search(tools%tool(t)%surface, tools%tool(t)%surface%mode, k, &
                                  nodes, node_normals, positions(:, t), limits%reach, &
                                  lock(first + 1:first + k), patch, params, points, normals, &
                                  tangents, distance, status, iterations, ncandidates, m, &
                                  memory(:, first + 1:first + m), &
                                  memory_patch(first + 1:first + m))
    end subroutine search_tool

    !> Outward normals of the blank at the k slaves of tool t (pairs a..): the sum of the
    !> area vectors, at x, of the boundary faces that faced the tool at the start; the
    !> tool's facing direction where a slave has none. Normalized twice, as the search's
    !> own normalization of its input would.
    subroutine facing_normals(t, k, out)
      integer, intent(in) :: t, k
      real(wp), intent(out) :: out(3, k)
      real(wp) :: area(3), e1(3), e2(3), length
      integer :: f, q, s, pass
      out = 0.0_wp
      do f = tools%face_first(t) + 1, tools%face_first(t + 1)
        e1 = x(:, tools%faces(3, f) + 1) - x(:, tools%faces(1, f) + 1)
        e2 = x(:, tools%faces(4, f) + 1) - x(:, tools%faces(2, f) + 1)
        area = 0.5_wp*[e1(2)*e2(3) - e1(3)*e2(2), e1(3)*e2(1) - e1(1)*e2(3), &
                       e1(1)*e2(2) - e1(2)*e2(1)]
        do q = 1, 4
          s = tools%corner(q, f)
          if (s >= 0) out(:, s + 1) = out(:, s + 1) + area
        end do
      end do
      do s = 1, k
        do pass = 1, 2
          length = sqrt(out(1, s)**2 + out(2, s)**2 + out(3, s)**2)
          if (length > 0.0_wp) then
            out(:, s) = out(:, s)/length
          else
            out(:, s) = tools%tool(t)%facing
          end if
        end do
      end do
    end subroutine facing_normals

    !> The pairs the first iteration's predictor closes (shut), with p_aug of every pair.
    subroutine touching_pairs()
      real(wp), allocatable :: rows(:, :)
      logical, allocatable :: at_rest(:)
      real(wp) :: d, centre(3), scale, axis(3)
      integer :: nrow, u, n, p, i, j
      logical :: any_resting
      allocate(at_rest(ntool))
      any_resting = .false.
      do u = 1, ntool
        at_rest(u) = searched(u) .and. all(positions(:, u) == positions_n(:, u))
        if (.not. searched(u)) cycle
        do p = pairs%tool_first(u) + 1, pairs%tool_first(u + 1)
          d = 0.0_wp
          if (status(p) /= contact_none) d = gap(p)
          p_aug(p) = force(1, p)*normal(1, p) + force(2, p)*normal(2, p) + &
                     force(3, p)*normal(3, p) - law%r(p)*d
          shut(p) = status(p) /= contact_none .and. p_aug(p) <= 0.0_wp .and. &
                    abs(d) <= touching .and. tools%tool(u)%discretization /= contact_gauss
          if (at_rest(u) .and. shut(p)) any_resting = .true.
        end do
      end do
      if (limits%resting .or. .not. any_resting) return
      ! The rigid modes the supports and the holding pairs stop: if all six, the
      ! touching pairs of the resting tools stay open.
      n = nnode
      centre = sum(x_n, dim=2)/real(n, wp)
      scale = max(maxval(maxval(x_n, dim=2) - minval(x_n, dim=2)), 1.0e-300_wp)
      nrow = count(dofs%fixed) + npair
      allocate(rows(6, max(nrow, 1)))
      nrow = 0
      do i = 1, nnode
        do j = 1, 3
          if (.not. dofs%fixed(j, i)) cycle
          nrow = nrow + 1
          axis = 0.0_wp
          axis(j) = 1.0_wp
          rows(:, nrow) = mode_row(x_n(:, i), axis, centre, scale)
        end do
      end do
      do u = 1, ntool
        if (.not. searched(u)) cycle
        do p = pairs%tool_first(u) + 1, pairs%tool_first(u + 1)
          if (status(p) == contact_none) cycle
          if (p_aug(p) > 0.0_wp .or. (.not. at_rest(u) .and. shut(p))) then
            nrow = nrow + 1
            rows(:, nrow) = mode_row(x(:, pairs%node(p) + 1), normal(:, p), centre, scale)
          end if
        end do
      end do
      if (nrow == 0) then
        nrow = 1
        rows(:, 1) = 0.0_wp
      end if
      if (rank_of_rows(nrow, rows(:, 1:nrow)) == 6) then
        do u = 1, ntool
          if (at_rest(u)) shut(pairs%tool_first(u) + 1:pairs%tool_first(u + 1)) = .false.
        end do
      end if
    end subroutine touching_pairs

  end subroutine forming_contact

  !> The six rigid modes of the blank (unit translations, rotations about its centre with
  !> the arm over the blank's size) along direction d at point y.
  pure function mode_row(y, d, centre, scale) result(row)
    real(wp), intent(in) :: y(3), d(3), centre(3), scale
    real(wp) :: row(6), arm(3)
    arm = (y - centre)/scale
    row(1:3) = d
    row(4) = arm(2)*d(3) - arm(3)*d(2)
    row(5) = arm(3)*d(1) - arm(1)*d(3)
    row(6) = arm(1)*d(2) - arm(2)*d(1)
  end function mode_row

  !> Rank of the nrow x 6 matrix whose rows are rows(:, i): its singular values above
  !> rank_tolerance, by one-sided Jacobi rotations of its six columns (accurate to the
  !> rounding of the entries, where a 6 x 6 normal matrix would square it).
  pure integer function rank_of_rows(nrow, rows) result(rank)
    integer, intent(in) :: nrow
    real(wp), intent(in) :: rows(6, nrow)
    real(wp), allocatable :: a(:, :), col(:)
    real(wp) :: alpha, beta, gamma, zeta, tn, cs, sn, off
    integer :: sweep, i, j
    ! Heap, not stack: the rows are every fixed dof and holding pair of the blank.
    allocate(a(nrow, 6), col(nrow))
    a = transpose(rows)
    do sweep = 1, 60
      off = 0.0_wp
      do i = 1, 5
        do j = i + 1, 6
          alpha = sum(a(:, i)**2)
          beta = sum(a(:, j)**2)
          gamma = sum(a(:, i)*a(:, j))
          if (gamma == 0.0_wp) cycle
          off = max(off, abs(gamma)/sqrt(max(alpha*beta, tiny(1.0_wp))))
          zeta = (beta - alpha)/(2.0_wp*gamma)
          tn = sign(1.0_wp, zeta)/(abs(zeta) + sqrt(1.0_wp + zeta*zeta))
          cs = 1.0_wp/sqrt(1.0_wp + tn*tn)
          sn = cs*tn
          col = a(:, i)
          a(:, i) = cs*col - sn*a(:, j)
          a(:, j) = sn*col + cs*a(:, j)
        end do
      end do
      if (off < 1.0e-15_wp) exit
    end do
    rank = 0
    do i = 1, 6
      if (sqrt(sum(a(:, i)**2)) > rank_tolerance) rank = rank + 1
    end do
  end function rank_of_rows

  !> The n Gauss-Legendre points on [-1, 1], ascending: the roots of the Legendre
  !> polynomial P_n by Newton's method from Tricomi's estimates (the weights, which the
  !> core does not need, come with the points' areas from the caller).
  pure subroutine gauss_legendre(n, xi)
    integer, intent(in) :: n
    real(wp), intent(out) :: xi(n)
    real(wp), parameter :: pi = acos(-1.0_wp)
    real(wp) :: z, p0, p1, p2, dp
    integer :: i, k, it
    do i = 1, (n + 1)/2
      z = cos(pi*(i - 0.25_wp)/(n + 0.5_wp))
      do it = 1, 100
        p0 = 1.0_wp
        p1 = z
        do k = 2, n
          p2 = ((2*k - 1)*z*p1 - (k - 1)*p0)/k
          p0 = p1
          p1 = p2
        end do
        if (n == 1) p0 = 1.0_wp
        dp = n*(z*p1 - p0)/(z*z - 1.0_wp)
        if (n == 1) dp = 1.0_wp
        z = z - p1/dp
        if (abs(p1/dp) < 1.0e-15_wp) exit
      end do
      xi(n + 1 - i) = z
      xi(i) = -z
    end do
    if (mod(n, 2) == 1) xi((n + 1)/2) = 0.0_wp
  end subroutine gauss_legendre

  !> The cross product a x b.
  pure function cross3(a, b) result(c)
    real(wp), intent(in) :: a(3), b(3)
    real(wp) :: c(3)
    c = [a(2)*b(3) - a(3)*b(2), a(3)*b(1) - a(1)*b(3), a(1)*b(2) - a(2)*b(1)]
  end function cross3

end module ddpy_forming
