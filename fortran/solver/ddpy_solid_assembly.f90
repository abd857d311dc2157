!> Assembly of the hexahedral solid straight into MUMPS coordinate storage, in parallel.
!>
!> Every element owns a fixed range of slots, offsets(e)+1 .. offsets(e+1), of the value
!> array: the entries (i, j) of its 24 x 24 tangent, in the order j = 1..24, i = j..24
!> (symmetric: lower triangle) or i = 1..24 (unsymmetric), skipping constrained dofs. The
!> index arrays are built once per mesh and constraint set (solid_coo_pattern); the values
!> are rewritten at every iteration by the elements in parallel, without races and in an
!> order that does not depend on the number of threads. Internal forces are gathered into
!> the nodal vector after the parallel loop, element by element, so they are deterministic
!> too. Node indices here are 1-based; equation numbers 0-based (-1: constrained dof).
module ddpy_solid_assembly
  use ddpy_kinds, only: wp
  use ddpy_material, only: material_prop_count, material_kinematic
  use ddpy_hex8, only: hex8_element, hex8_jacobians, hex8_stresses, hex8_ok
  use ddpy_solid_shell, only: solid_shell_element, shell_modes
  implicit none
  private
  public :: solid_jacobians, solid_coo_count, solid_coo_pattern, solid_assemble, &
            solid_stresses, shell_modes

  !> Element kinds of a mesh: the mean-dilatation hexahedron (ddpy_hex8) and the
  !> solid-shell (ddpy_solid_shell), which carries shell_modes enhanced parameters per
  !> element through the iterations of an increment.
  integer, parameter, public :: kind_hexahedron = 0, kind_solid_shell = 1
  !> Status of solid_assemble when the backstress arrays do not fit the mesh.
  integer, parameter, public :: status_back_size = 7

contains

  !> Equation numbers of the 24 element dofs (node-major: 3 (a-1) + component).
  pure function element_equations(nodes, nn, eqn) result(eq)
    integer, intent(in) :: nodes(8), nn, eqn(3, nn)
    integer :: eq(24)
    integer :: a
    do a = 1, 8
      eq(3*a - 2:3*a) = eqn(:, nodes(a))
    end do
  end function element_equations

  !> det J0 of every element at its Gauss points (1:8) and corners (9:16).
  subroutine solid_jacobians(nn, x, ne, conn, detj)
    integer, intent(in) :: nn, ne, conn(8, ne)
    real(wp), intent(in) :: x(3, nn)
    real(wp), intent(out) :: detj(16, ne)
    integer :: e
    !$omp parallel do schedule(static) if(ne > 256)
    do e = 1, ne
      call hex8_jacobians(x(:, conn(:, e)), detj(:, e))
    end do
    !$omp end parallel do
  end subroutine solid_jacobians

  !> Number of coordinate entries each element contributes.
  subroutine solid_coo_count(nn, ne, conn, eqn, symmetric, counts)
    integer, intent(in) :: nn, ne, conn(8, ne), eqn(3, nn)
    logical, intent(in) :: symmetric
    integer, intent(out) :: counts(ne)
    integer :: e, nfree
    !$omp parallel do schedule(static) private(nfree) if(ne > 256)
    do e = 1, ne
      nfree = count(element_equations(conn(:, e), nn, eqn) >= 0)
      if (symmetric) then
        counts(e) = nfree*(nfree + 1)/2
      else
        counts(e) = nfree*nfree
      end if
    end do
    !$omp end parallel do
  end subroutine solid_coo_count

  !> Row and column (0-based equation numbers) of every slot; for the symmetric storage
  !> row >= col.
  subroutine solid_coo_pattern(nn, ne, conn, eqn, symmetric, offsets, nz, rows, cols)
    integer, intent(in) :: nn, ne, conn(8, ne), eqn(3, nn), offsets(ne + 1), nz
    logical, intent(in) :: symmetric
    integer, intent(out) :: rows(nz), cols(nz)
    integer :: e, i, j, pos, eq(24)
    !$omp parallel do schedule(static) private(i, j, pos, eq) if(ne > 256)
    do e = 1, ne
      eq = element_equations(conn(:, e), nn, eqn)
      pos = offsets(e)
      do j = 1, 24
        if (eq(j) < 0) cycle
        do i = merge(j, 1, symmetric), 24
          if (eq(i) < 0) cycle
          pos = pos + 1
          if (symmetric) then
            rows(pos) = max(eq(i), eq(j))
            cols(pos) = min(eq(i), eq(j))
          else
            rows(pos) = eq(i)
            cols(pos) = eq(j)
          end if
        end do
      end do
    end do
    !$omp end parallel do
  end subroutine solid_coo_pattern

  !> Internal forces, tangent values (when want_tangent) and trial material state of the
  !> whole mesh of elements of the given kind at total displacements u, over the increment
  !> from the converged state at displacements u_ref (the reference configuration x + u_ref
  !> of the updated Lagrangian element). props: one material; state per Gauss point as in
  !> hex8_element. alpha_in: the start of the solid-shell's enhanced parameters (the
  !> previous iterate's, zero at the start of an increment), alpha their solution (alpha =
  !> alpha_in for the hexahedron). With
  !> want_product (and want_tangent), kdu = K dp, the tangent times the vector dp (the
  !> increment of the prescribed displacements: the linearized predictor of an increment),
  !> otherwise kdu = 0. back_old, back (6, 8, nback): the backstress of mixed hardening
  !> (material_kinematic(props)), nback = ne; without it nback may be anything from 0 and
  !> they are not touched. status = hex8_ok, or the status of the first failing element,
  !> whose index is returned in element (0 when none; status_back_size and 0 when nback
  !> does not fit).
  subroutine solid_assemble(nn, x, ne, conn, kind, u_ref, u, props, axes_old, stress_old, &
                            ep_old, strain_old, nback, back_old, alpha_in, eqn, symmetric, &
                            want_tangent, offsets, nz, values, want_product, dp, fint, kdu, &
                            stress, ep, strain, axes, back, alpha, status, element)
    integer, intent(in) :: nn, ne, nz, conn(8, ne), kind, eqn(3, nn), offsets(ne + 1), nback
    real(wp), intent(in) :: x(3, nn), u_ref(3, nn), u(3, nn), props(material_prop_count)
    real(wp), intent(in) :: axes_old(3, 3, 8, ne), stress_old(6, 8, ne), ep_old(8, ne), &
                            strain_old(6, 8, ne), back_old(6, 8, nback), &
                            alpha_in(shell_modes, ne)
    real(wp), intent(in) :: dp(3, nn)
    logical, intent(in) :: symmetric, want_tangent, want_product
    real(wp), intent(inout) :: values(nz), back(6, 8, nback)
    real(wp), intent(out) :: fint(3, nn), kdu(3, nn), stress(6, 8, ne), ep(8, ne), &
                             strain(6, 8, ne), axes(3, 3, 8, ne), alpha(shell_modes, ne)
    integer, intent(out) :: status, element
    real(wp), allocatable :: fe(:, :), ke_dp(:, :)
    integer, allocatable :: estatus(:)
    integer :: e, a
    logical :: product, kinematic

    product = want_tangent .and. want_product
    kinematic = material_kinematic(props)
    if (kinematic .and. nback /= ne) then
      status = status_back_size
      element = 0
      fint = 0.0_wp
      kdu = 0.0_wp
      return
    end if
    allocate (fe(24, ne), estatus(ne))
    if (product) then
      allocate (ke_dp(24, ne))
    else
      allocate (ke_dp(24, 1))
    end if
    !$omp parallel do schedule(dynamic, 16) if(ne > 256)
    do e = 1, ne
      call assemble_element(e, nn, x, ne, conn, kind, u_ref, u, props, axes_old, &
                            stress_old, ep_old, strain_old, kinematic, nback, back_old, &
                            alpha_in(:, e), eqn, symmetric, &
                            want_tangent, offsets, nz, values, product, dp, fe(:, e), &
                            ke_dp(:, min(e, size(ke_dp, 2))), stress(:, :, e), ep(:, e), &
                            strain(:, :, e), axes(:, :, :, e), back, alpha(:, e), estatus(e))
    end do
    !$omp end parallel do

    status = hex8_ok
    element = 0
    do e = 1, ne
      if (estatus(e) /= hex8_ok) then
        status = estatus(e)
        element = e
        exit
      end if
    end do
    fint = 0.0_wp
    do e = 1, ne
      do a = 1, 8
        fint(:, conn(a, e)) = fint(:, conn(a, e)) + fe(3*a - 2:3*a, e)
      end do
    end do
    kdu = 0.0_wp
    if (.not. product) return
    do e = 1, ne
      do a = 1, 8
        kdu(:, conn(a, e)) = kdu(:, conn(a, e)) + ke_dp(3*a - 2:3*a, e)
      end do
    end do
  end subroutine solid_assemble

  !> One element of solid_assemble: writes only its own slots and state columns.
  subroutine assemble_element(e, nn, x, ne, conn, kind, u_ref, u, props, axes_old, &
                              stress_old, ep_old, strain_old, kinematic, nback, back_old, &
                              alpha_in, eqn, symmetric, &
                              want_tangent, offsets, nz, values, product, dp, fe, ke_dp, &
                              stress, ep, strain, axes, back, alpha, status)
    integer, intent(in) :: e, nn, ne, nz, conn(8, ne), kind, eqn(3, nn), offsets(ne + 1), &
                           nback
    real(wp), intent(in) :: x(3, nn), u_ref(3, nn), u(3, nn), props(material_prop_count)
    real(wp), intent(in) :: axes_old(3, 3, 8, ne), stress_old(6, 8, ne), ep_old(8, ne), &
                            strain_old(6, 8, ne), back_old(6, 8, nback), alpha_in(shell_modes)
    real(wp), intent(in) :: dp(3, nn)
    logical, intent(in) :: symmetric, want_tangent, product, kinematic
    real(wp), intent(inout) :: values(nz), back(6, 8, nback)
    real(wp), intent(out) :: fe(24), ke_dp(24), stress(6, 8), ep(8), strain(6, 8), &
                             axes(3, 3, 8), alpha(shell_modes)
    integer, intent(out) :: status
    real(wp) :: ke(24, 24), x0(3, 8), xn(3, 8), du(3, 8), de(24), back_e(6, 8), &
                back_in(6, 8)
    integer :: eq(24), i, j, pos, a

    do a = 1, 8
      x0(:, a) = x(:, conn(a, e))
      xn(:, a) = x0(:, a) + u_ref(:, conn(a, e))
      du(:, a) = u(:, conn(a, e)) - u_ref(:, conn(a, e))
    end do
    ! Without kinematic hardening the elements do not read the backstress: zeros stand in.
    if (kinematic) then
      back_in = back_old(:, :, e)
    else
      back_in = 0.0_wp
    end if
    if (kind == kind_solid_shell) then
      call solid_shell_element(x0, xn, du, props, axes_old(:, :, :, e), stress_old(:, :, e), &
                               ep_old(:, e), strain_old(:, :, e), back_in, alpha_in, &
                               want_tangent, fe, ke, stress, ep, strain, axes, back_e, alpha, &
                               status)
    else
      alpha = alpha_in
      call hex8_element(x0, xn, du, props, axes_old(:, :, :, e), stress_old(:, :, e), &
                        ep_old(:, e), strain_old(:, :, e), back_in, want_tangent, fe, ke, &
                        stress, ep, strain, axes, back_e, status)
    end if
    if (kinematic) back(:, :, e) = back_e
    if (.not. want_tangent .or. status /= hex8_ok) return
    if (product) then
      do a = 1, 8
        de(3*a - 2:3*a) = dp(:, conn(a, e))
      end do
      ke_dp = matmul(ke, de)
    end if
    eq = element_equations(conn(:, e), nn, eqn)
    pos = offsets(e)
    if (all(eq >= 0)) then
      ! No constrained dof (most elements): whole column pieces, copied as blocks.
      do j = 1, 24
        i = merge(j, 1, symmetric)
        values(pos + 1:pos + 25 - i) = ke(i:24, j)
        pos = pos + 25 - i
      end do
      return
    end if
    do j = 1, 24
      if (eq(j) < 0) cycle
      do i = merge(j, 1, symmetric), 24
        if (eq(i) < 0) cycle
        pos = pos + 1
        values(pos) = ke(i, j)
      end do
    end do
  end subroutine assemble_element

  !> Second Piola-Kirchhoff and Cauchy stresses (global axes) and current positions at the
  !> Gauss points from the state (material axes, rotated Kirchhoff stress) at total
  !> displacements u; status as in solid_assemble.
  subroutine solid_stresses(nn, x, ne, conn, u, axes, stress_mat, pk2, cauchy, points, &
                            status, element)
    integer, intent(in) :: nn, ne, conn(8, ne)
    real(wp), intent(in) :: x(3, nn), u(3, nn), axes(3, 3, 8, ne), stress_mat(6, 8, ne)
    real(wp), intent(out) :: pk2(6, 8, ne), cauchy(6, 8, ne), points(3, 8, ne)
    integer, intent(out) :: status, element
    integer, allocatable :: estatus(:)
    integer :: e
    allocate (estatus(ne))
    !$omp parallel do schedule(static) if(ne > 256)
    do e = 1, ne
      call hex8_stresses(x(:, conn(:, e)), u(:, conn(:, e)), axes(:, :, :, e), &
                         stress_mat(:, :, e), pk2(:, :, e), cauchy(:, :, e), &
                         points(:, :, e), estatus(e))
    end do
    !$omp end parallel do
    status = hex8_ok
    element = 0
    do e = 1, ne
      if (estatus(e) /= hex8_ok) then
        status = estatus(e)
        element = e
        exit
      end if
    end do
  end subroutine solid_stresses

end module ddpy_solid_assembly
