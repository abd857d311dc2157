!> The Jacobian's layout of a forming problem (or of the static problem, one without tools),
!> computed by the core once per problem from its blank, constraints, tools, pairs and
!> force-controlled tools: the coordinate structure MUMPS analyses (ddpy.model.newton.Layout
!> reads it through problem_layout) and in whose slots the Newton loop writes the values.
!>
!> The unknowns: the free displacement dofs (eqn), then 3 force components per pair, then
!> one displacement per force-controlled tool. The slots, in the order the evaluation
!> writes them:
!>   1. the solid's tangent (ddpy_solid_assembly, solid_coo_pattern): k_slots of them;
!>   2. the coupling entries (node's equilibrium row, multiplier) of every free component of
!>      every pair, pair after pair: -1, or 0 where the multiplier is eliminated (a
!>      Gauss-point pair without a barrier: lambda = F(x), ddpy_forming_newton);
!>   3. dC/dx over the free dofs of each pair's patch (pair, row, patch node, column); a
!>      held component of a surface-to-surface or Gauss-point pair (a slave on a symmetry
!>      plane, law lambda_k = 0) has none, since in its row they would join the patch's
!>      nodes to one another through the multiplier (the paper's bending mesh took 81
!>      million factor entries instead of 59 for these 410 pairs); a Gauss-point pair's
!>      entries, -dF/dx, lie in its node's equilibrium rows, where the faces' nodes already
!>      couple (no fill), and a barrier pair's own law (ddpy_forming) follows them: dC/dx
!>      at its node's free dofs (row, column), in its law rows;
!>   4. dC/dlambda (pair, row, column): contact_values slots up to here (ddpy_forming);
!>   5. per force-controlled tool (ddpy_forming_newton, hold_equations): its column (per
!>      pair, a Gauss-point pair's free equilibrium rows, then the 3 law rows of a pair
!>      with a multiplier), its row (a . lambda_p of each pair with a multiplier: the
!>      constant a_j at lambda_p,j; then for each Gauss-point pair -a_i times each of its
!>      -dF_i/dx entries, their source slots) and its diagonal.
module ddpy_jacobian_layout
  use ddpy_kinds, only: wp
  use ddpy_blank, only: blank_mesh, blank_dofs
  use ddpy_forming_data, only: tool_set, pair_set, force_holds, contact_node, contact_gauss, &
                               has_barrier
  use ddpy_solid_assembly, only: solid_coo_pattern
  implicit none
  private
  public :: jacobian_layout, layout_build

  !> The layout: n unknowns, nvalues coordinate slots (rows, cols: 0-based), of which
  !> k_slots the solid's, ncoupling the coupling entries (their values, coupling) and
  !> contact_values the solid's with the contact blocks'; per pair, whether its multiplier
  !> is eliminated, and whether it is a barrier pair (a Gauss-point pair with a multiplier
  !> of its own). built: computed for the present tools and holds.
  type :: jacobian_layout
    logical :: built = .false.
    integer :: n = 0, nvalues = 0, k_slots = 0, ncoupling = 0, contact_values = 0
    integer, allocatable :: rows(:), cols(:)       !< (nvalues)
    real(wp), allocatable :: coupling(:)           !< (ncoupling)
    logical, allocatable :: eliminated(:)          !< (npair)
    logical, allocatable :: barrier(:)             !< (npair)
  end type jacobian_layout

contains

  !> The layout of the problem of blank, dofs, tools, pairs and holds (the tools and axes of
  !> the force-controlled tools); it writes the holds' rows (first, source, coef) too.
  !> Counted in a first pass, written in a second.
  subroutine layout_build(blank, dofs, tools, pairs, holds, layout)
    type(blank_mesh), intent(in) :: blank
    type(blank_dofs), intent(in) :: dofs
    type(tool_set), intent(in) :: tools
    type(pair_set), intent(in) :: pairs
    type(force_holds), intent(inout) :: holds
    type(jacobian_layout), intent(out) :: layout
    logical, allocatable :: patched(:), lumped(:)
    integer, allocatable :: patch_slot(:)
    integer :: pass, slot, nsource, nf, npair, t, p, i, j, e, k, node_eq, col, row, s
    logical :: fill
    nf = dofs%nf
    npair = pairs%npair
    allocate(layout%eliminated(npair), layout%barrier(npair), patched(npair), lumped(npair), &
             patch_slot(npair))
    do t = 1, tools%ntool
      lumped(pairs%tool_first(t) + 1:pairs%tool_first(t + 1)) = &
        tools%tool(t)%discretization == contact_gauss
      layout%barrier(pairs%tool_first(t) + 1:pairs%tool_first(t + 1)) = has_barrier(tools%tool(t))
      layout%eliminated(pairs%tool_first(t) + 1:pairs%tool_first(t + 1)) = &
        tools%tool(t)%discretization == contact_gauss .and. .not. has_barrier(tools%tool(t))
      patched(pairs%tool_first(t) + 1:pairs%tool_first(t + 1)) = &
        tools%tool(t)%discretization /= contact_node
    end do
    layout%n = nf + 3*npair + holds%nhold
    layout%k_slots = dofs%k_slots
    do pass = 1, 2
      fill = pass == 2
      if (fill) then
        allocate(layout%rows(layout%nvalues), layout%cols(layout%nvalues), &
                 layout%coupling(layout%ncoupling))
        if (allocated(holds%source)) deallocate(holds%source, holds%coef, holds%first)
        allocate(holds%source(nsource), holds%coef(nsource), holds%first(holds%nhold + 1))
        holds%nsource = nsource
        holds%first(1) = 0
        call solid_coo_pattern(blank%nnode, blank%ne, blank%conn, dofs%eqn, dofs%symmetric, &
                               dofs%offsets, dofs%k_slots, layout%rows(1:dofs%k_slots), &
                               layout%cols(1:dofs%k_slots))
      end if
      slot = dofs%k_slots
      do p = 1, npair  ! the coupling entries
        do i = 1, 3
          node_eq = dofs%eqn(i, pairs%node(p) + 1)
          if (node_eq < 0) cycle
          slot = slot + 1
          if (.not. fill) cycle
          call put(slot, node_eq, law_row(p, i))
          layout%coupling(slot - dofs%k_slots) = merge(0.0_wp, -1.0_wp, layout%eliminated(p))
        end do
      end do
      if (.not. fill) layout%ncoupling = slot - dofs%k_slots
      do p = 1, npair  ! dC/dx over the patch
        patch_slot(p) = slot
        do i = 1, 3
          node_eq = dofs%eqn(i, pairs%node(p) + 1)
          if (patched(p) .and. node_eq < 0) cycle
          row = law_row(p, i)
          if (lumped(p) .and. node_eq >= 0) row = node_eq
          do e = pairs%patch_first(p) + 1, pairs%patch_first(p + 1)
            do j = 1, 3
              col = dofs%eqn(j, pairs%patch_node(e) + 1)
              if (col < 0) cycle
              slot = slot + 1
              if (fill) call put(slot, row, col)
            end do
          end do
        end do
        if (.not. layout%barrier(p)) cycle
        do i = 1, 3  ! a barrier pair's own law: its node alone
          do j = 1, 3
            col = dofs%eqn(j, pairs%node(p) + 1)
            if (col < 0) cycle
            slot = slot + 1
            if (fill) call put(slot, law_row(p, i), col)
          end do
        end do
      end do
      do p = 1, npair  ! dC/dlambda
        do i = 1, 3
          do j = 1, 3
            slot = slot + 1
            if (fill) call put(slot, law_row(p, i), law_row(p, j))
          end do
        end do
      end do
      layout%contact_values = slot
      nsource = 0
      do k = 1, holds%nhold
        t = holds%tool(k)
        row = nf + 3*npair + k - 1
        do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)  ! its column
          do i = 1, 3
            if (.not. lumped(p)) exit
            col = dofs%eqn(i, pairs%node(p) + 1)
            if (col < 0) cycle
            slot = slot + 1
            if (fill) call put(slot, col, row)
          end do
          if (layout%eliminated(p)) cycle
          do i = 1, 3
            slot = slot + 1
            if (fill) call put(slot, law_row(p, i), row)
          end do
        end do
        do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)  ! its row: the multipliers
          if (layout%eliminated(p)) cycle
          do i = 1, 3
            slot = slot + 1
            nsource = nsource + 1
            if (.not. fill) cycle
            call put(slot, row, law_row(p, i))
            holds%source(nsource) = -1
            holds%coef(nsource) = holds%axis(i, k)
          end do
        end do
        do p = pairs%tool_first(t) + 1, pairs%tool_first(t + 1)  ! and the F(x) entries
          if (.not. lumped(p)) cycle
          s = patch_slot(p)
          do i = 1, 3
            if (dofs%eqn(i, pairs%node(p) + 1) < 0) cycle  ! (patched: a held row has none)
            do e = pairs%patch_first(p) + 1, pairs%patch_first(p + 1)
              do j = 1, 3
                if (dofs%eqn(j, pairs%patch_node(e) + 1) < 0) cycle
                s = s + 1
                slot = slot + 1
                nsource = nsource + 1
                if (.not. fill) cycle
                call put(slot, row, layout%cols(s))
                holds%source(nsource) = s - 1
                holds%coef(nsource) = -holds%axis(i, k)
              end do
            end do
          end do
        end do
        slot = slot + 1  ! its diagonal
        if (fill) then
          call put(slot, row, row)
          holds%first(k + 1) = nsource
        end if
      end do
      layout%nvalues = slot
    end do
    layout%built = .true.

  contains

    !> The 0-based row of component i of pair p's law.
    pure integer function law_row(p, i)
      integer, intent(in) :: p, i
      law_row = nf + 3*(p - 1) + i - 1
    end function law_row

    !> Slot s at (r, c).
    subroutine put(s, r, c)
      integer, intent(in) :: s, r, c
      layout%rows(s) = r
      layout%cols(s) = c
    end subroutine put

  end subroutine layout_build

end module ddpy_jacobian_layout
